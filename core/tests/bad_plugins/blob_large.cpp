// One of two plugins built against different definitions of the data type test.Blob (this one:
// 16 bytes): loaded together they would exchange objects of the wrong size.
#include <fba/plugin.hpp>
namespace test_blob {
struct Blob {
  std::int64_t a, b;
};
}  // namespace test_blob
FBA_DATA_TYPE(test_blob::Blob, "test.Blob", "A test type with two definitions.");
namespace {
class Source final : public fba::Component {
 public:
  static constexpr fba::Out<test_blob::Blob> kOut{"out", "blobs"};
  static fba::Spec spec() { return fba::Spec::sensor("test.blob_large", "Sends test.Blob (16 bytes).").add(kOut); }
  explicit Source(fba::Context&) {}
  void process() override {}
};
}  // namespace
FBA_COMPONENT(Source);
FBA_PLUGIN("blob_large")
