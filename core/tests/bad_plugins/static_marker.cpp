// A plugin whose static initialiser leaves a mark (a file named by FBA_TEST_MARKER), so a test
// can tell whether any of its code ran.
#include <cstdlib>
#include <fstream>

#include <fba/plugin.hpp>
namespace {
const bool marked = [] {
  if (const char* file = std::getenv("FBA_TEST_MARKER")) std::ofstream(file) << "static initialiser ran\n";
  return true;
}();
class Marker final : public fba::Component {
 public:
  static constexpr fba::Out<std::int64_t> kOut{"out", "nothing"};
  static fba::Spec spec() { return fba::Spec::sensor("test.marker", "Leaves a mark when its plugin is loaded.").add(kOut); }
  explicit Marker(fba::Context&) {}
  void process() override {}
};
}  // namespace
FBA_COMPONENT(Marker);
FBA_PLUGIN("static_marker")
