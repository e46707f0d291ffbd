// The plugins blob_small and blob_large, each built from this file against its own definition of
// the data type test.Blob (BLOB_WORDS 64-bit words: 8 or 16 bytes; BLOB_PLUGIN its name): loaded
// together they would exchange objects of the wrong size.
#include <fba/plugin.hpp>
namespace test_blob {
struct Blob {
  std::int64_t words[BLOB_WORDS];
};
}  // namespace test_blob
FBA_DATA_TYPE(test_blob::Blob, "test.Blob", "A test type with two definitions.");
namespace {
class Source final : public fba::Component {
 public:
  static constexpr fba::Out<test_blob::Blob> kOut{"out", "blobs"};
  static fba::Spec spec() {
    return fba::Spec::sensor("test." BLOB_PLUGIN, "Sends test.Blob, in one of its two sizes.").add(kOut);
  }
  explicit Source(fba::Context&) {}
  void process() override {}
};
}  // namespace
FBA_COMPONENT(Source);
FBA_PLUGIN(BLOB_PLUGIN)
