// Test harnesses. ComponentHarness drives one component by hand (push samples, run, read
// outputs and events) on a clock the test advances, like GstHarness with its test clock; for
// whole tasks, use fba::Task with Task::tap and the deterministic executor.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "fba/packet.hpp"
#include "fba/registry.hpp"
#include "fba/spec.hpp"
#include "fba/task.hpp"
#include "fba/value.hpp"

namespace fba::testing {

// Parameter values by name, typed: {{"count", 5}, {"rate", 2.5}, {"bounds", std::vector<double>{...}}}.
using Params = std::map<std::string, Value>;

class ComponentHarness {
 public:
  // `params` are checked exactly as a task file's values are (type, range, choices, list
  // lengths, the spec's checks); an int is taken for a double parameter, as in a task file.
  // Relative paths are taken from the working folder. Required inputs are connected to the
  // harness; optional ones only when named in `optional_inputs` (a component may behave
  // differently without them). Throws ConfigError (a plugin bug is one too, at the plugin).
  ComponentHarness(const Registry& registry, const std::string& type, const Params& params = {},
                   const std::vector<std::string>& optional_inputs = {});
  ~ComponentHarness();

  // A sample on an input, stamped `stamp_ns` (default: the harness clock's time).
  template <class T>
  void push(const std::string& input, T value, std::int64_t stamp_ns = -1) {
    push_packet(input, Packet::make<T>(std::make_shared<const T>(std::move(value)), Header{next_seq_++, stamp(stamp_ns), nullptr}));
  }
  template <class T>
  void push(const In<T>& input, T value, std::int64_t stamp_ns = -1) { push<T>(std::string(input.name), std::move(value), stamp_ns); }
  template <class T>
  void push(const OptionalIn<T>& input, T value, std::int64_t stamp_ns = -1) {
    push<T>(std::string(input.name), std::move(value), stamp_ns);
  }
  // A packet as it is (its own header): to replay samples another harness produced.
  void push_packet(const std::string& input, Packet p);
  // The input's producer has finished: once drained, the component sees the end of stream.
  void close(const std::string& input);

  // The clock the component sees (Context::now_ns) and pushes are stamped with; starts at 0
  // and moves only when the test moves it.
  std::int64_t now_ns() const;
  void advance(std::int64_t ns);
  void set_time(std::int64_t ns);
  // Periodic components: one tick of the period (the clock advances by the period).
  void tick();
  // Runs invocations while the trigger policy allows; returns how many ran.
  int run();
  // Runs at most one invocation.
  bool step();

  const std::vector<Packet>& packets(const std::string& output);
  template <class T>
  std::vector<T> values(const std::string& output) {
    std::vector<T> out;
    for (const auto& p : packets(output)) out.push_back(p.get<T>());
    return out;
  }
  template <class T>
  std::vector<T> values(const Out<T>& output) { return values<T>(std::string(output.name)); }
  std::vector<Event> events() const;
  bool finished() const;
  // Why the component stopped the task (an exception), empty if it did not.
  std::string failure() const;
  std::string stage() const;
  void safe_state();
  void interrupt();

 private:
  std::int64_t stamp(std::int64_t given) const { return given >= 0 ? given : now_ns(); }
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::uint64_t next_seq_ = 0;
};

}  // namespace fba::testing
