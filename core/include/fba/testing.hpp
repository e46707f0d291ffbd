// Test harnesses. ComponentHarness drives one component by hand (push samples, run, read
// outputs and events), like GstHarness; for whole tasks, use fba::Task with Task::tap and the
// deterministic executor.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "fba/packet.hpp"
#include "fba/registry.hpp"
#include "fba/task.hpp"

namespace fba::testing {

class ComponentHarness {
 public:
  // `params` are YAML values as a task file would write them ({"count", "5"}); they are checked
  // exactly as in a task file. Required inputs are connected to the harness; optional ones
  // only when named in `optional_inputs` (a component may behave differently without them).
  // Throws ConfigError.
  ComponentHarness(const Registry& registry, const std::string& type, const std::map<std::string, std::string>& params = {},
                   const std::vector<std::string>& optional_inputs = {});
  ~ComponentHarness();

  template <class T>
  void push(const std::string& input, T value, std::int64_t stamp_ns = 0) {
    push_packet(input, Packet::make<T>(std::make_shared<const T>(std::move(value)), Header{next_seq_++, stamp_ns, nullptr}));
  }
  void push_packet(const std::string& input, Packet p);
  // The input's producer has finished: once drained, the component sees the end of stream.
  void close(const std::string& input);
  // Periodic components: one tick of the period.
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
  std::vector<Event> events() const;
  bool finished() const;
  // Why the component stopped the task (an exception), empty if it did not.
  std::string failure() const;
  std::string stage() const;
  void safe_state();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::uint64_t next_seq_ = 0;
};

}  // namespace fba::testing
