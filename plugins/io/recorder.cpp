// io.recorder: writes every sample it receives, and every event delivered to it, as one line of
// JSON (JSON Lines) with its time stamp, so that a person (or jq) can read what a run carried.
// Events and the scalar types (fba.Int, fba.Double, fba.String) are written with their values;
// any other type with its name, sequence number, producer and size.
#include <cerrno>
#include <cstring>
#include <fstream>

#include <nlohmann/json.hpp>

#include <fba/component.hpp>

namespace {

class Recorder final : public fba::Component {
 public:
  static constexpr fba::AnyIn kIn{"in", "samples of any type, or events delivered by a rule ({ deliver: recorder.in })"};
  static constexpr fba::Param<std::string> kFile{
      "file", "record.jsonl", "where to write; a relative name lands in the run's --output-dir (absolute: anywhere)"};

  static fba::Spec spec() {
    return fba::Spec::actuator("io.recorder", "Records every sample and event it receives as JSON Lines with time stamps.")
        .add(kIn, kFile);
  }

  explicit Recorder(fba::Context& ctx) : in_(ctx(kIn)) {
    std::filesystem::path file = std::string(ctx(kFile));
    if (file.is_relative()) {
      if (ctx.output_dir().empty())
        throw std::invalid_argument("file '" + file.string() + "' is relative, so it goes in the run's output folder; run with " +
                                    "--output-dir, or give an absolute path");
      file = ctx.output_dir() / file;
    }
    out_.open(file, std::ios::out | std::ios::trunc);
    if (!out_) throw std::runtime_error("cannot write '" + file.string() + "': " + std::strerror(errno));
    file_ = file.string();
  }

  void process() override {
    const fba::Packet& p = in_.packet();
    const fba::Header& h = p.header();
    nlohmann::json line{{"t", static_cast<double>(h.stamp_ns) * 1e-9},
                        {"seq", h.seq},
                        {"producer", h.producer ? *h.producer : std::string()},
                        {"type", p.type()->name}};
    if (p.holds<fba::Event>()) {
      const auto& e = p.get<fba::Event>();
      line["value"] = {{"source", e.source}, {"name", e.name}, {"payload", e.payload}};
    } else if (p.holds<std::int64_t>()) {
      line["value"] = p.get<std::int64_t>();
    } else if (p.holds<double>()) {
      line["value"] = p.get<double>();
    } else if (p.holds<std::string>()) {
      line["value"] = p.get<std::string>();
    } else {
      line["bytes"] = p.bytes();
    }
    // One line at a time, flushed: a run that ends abruptly still leaves what it recorded.
    out_ << line.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << '\n' << std::flush;
    if (!out_) throw std::runtime_error("cannot write '" + file_ + "': " + std::strerror(errno));
  }

  void safe_state() override { out_.flush(); }

 private:
  fba::Input& in_;
  std::ofstream out_;
  std::string file_;
};

}  // namespace

FBA_COMPONENT(Recorder);
