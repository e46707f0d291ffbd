// Plugins are checked from their files (manifest, ELF header) before any of their code runs,
// loaded only when a task uses them, and refused with the file and the reason.
#include <dlfcn.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>

#include <fba/plugin.hpp>
#include <fba/registry.hpp>
#include <fba/task.hpp>
#include <fba/task_config.hpp>

#include "elf_file.hpp"
#include "plugin_manifest.hpp"
#include "support/temp_dir.hpp"
#include "fixture_components.hpp"
#include "support/build_paths.hpp"

namespace fs = std::filesystem;

namespace {

std::string refusal(const std::string& file, fba::Registry& r) {
  try {
    r.load_plugin(file);
  } catch (const fba::PluginError& e) {
    EXPECT_EQ(e.file(), file);
    return e.reason();
  }
  return "";
}

std::string bad(const std::string& name) { return fba::test::binary_dir() + "/core/tests/bad_plugins/" + name + ".so"; }
std::string examples() { return fba::test::plugin_dir() + "/fba-examples.so"; }

// A fresh folder per call, removed when the test ends.
fs::path temp_dir() { return fba::test::TempDir::until_exit(); }

// Copies a plugin (and its manifest, if it has one) into `dir`; returns the copy.
fs::path copy_plugin(const fs::path& so, const fs::path& dir) {
  fs::copy_file(so, dir / so.filename());
  const fs::path m = fba::detail::manifest_path(so);
  if (fs::exists(m)) fs::copy_file(m, dir / m.filename());
  return dir / so.filename();
}

// A manifest for a plugin that fba_add_plugin did not build: a valid record for this fba,
// with one component type, edited by the test.
void write_manifest(const fs::path& so, const std::function<void(fba::detail::Manifest&)>& edit = {}) {
  fba::detail::Manifest m;
  m.magic = fba::kPluginMagic;
  m.abi_version = fba::kAbiVersion;
  m.fba_version = FBA_VERSION;
  m.build_abi = FBA_BUILD_ABI_TAG;
  m.name = so.stem().string();
  m.build_id = fba::detail::check_elf(so).build_id;
  m.types.push_back({"test." + m.name, "filter", R"({"type": "test.)" + m.name + R"(", "kind": "filter"})"});
  if (edit) edit(m);
  std::ofstream(fba::detail::manifest_path(so)) << fba::detail::manifest_json(m);
}

void edit_manifest(const fs::path& so, const std::function<void(fba::detail::Manifest&)>& edit) {
  auto m = fba::detail::read_manifest(fba::detail::manifest_path(so));
  edit(m);
  std::ofstream(fba::detail::manifest_path(so)) << fba::detail::manifest_json(m);
}

// The files of a folder that are mapped into this process.
std::set<std::string> mapped_plugins(const fs::path& folder) {
  std::set<std::string> out;
  std::ifstream maps("/proc/self/maps");
  const std::string dir = fs::canonical(folder).string() + "/";
  for (std::string line; std::getline(maps, line);)
    if (auto at = line.find(dir); at != std::string::npos) out.insert(line.substr(at + dir.size()));
  return out;
}

class MarkerEnv {
 public:
  explicit MarkerEnv(const fs::path& marker) { setenv("FBA_TEST_MARKER", marker.c_str(), 1); }
  ~MarkerEnv() { unsetenv("FBA_TEST_MARKER"); }
};

}  // namespace

TEST(Plugin, AnotherAbiVersionInTheManifestIsRefusedBeforeAnyOfItsCodeRuns) {
  const fs::path dir = temp_dir();
  const fs::path so = copy_plugin(bad("static_marker"), dir);
  edit_manifest(so, [](auto& m) { m.abi_version = 999; m.fba_version = "9.9.9"; });
  const fs::path marker = dir / "marker";
  MarkerEnv env(marker);
  fba::Registry r;
  const auto why = refusal(so.string(), r);
  EXPECT_NE(why.find("was built for fba plugin ABI 999 (fba 9.9.9)"), std::string::npos) << why;
  EXPECT_FALSE(fs::exists(marker)) << "the plugin's static initialiser ran before its ABI was checked";
}

TEST(Plugin, TheMarkerPluginLeavesItsMarkWhenItIsLoaded) {
  // The counterpart of the test above: the mark does appear when the plugin's code runs.
  const fs::path dir = temp_dir();
  const fs::path so = copy_plugin(bad("static_marker"), dir);
  const fs::path marker = dir / "marker";
  MarkerEnv env(marker);
  fba::Registry r;
  EXPECT_TRUE(r.load_path({dir}).empty());
  EXPECT_FALSE(fs::exists(marker)) << "load_path ran plugin code";
  ASSERT_NE(r.find("test.marker"), nullptr);
  EXPECT_TRUE(fs::exists(marker));
}

TEST(Plugin, AnAbiRecordFromTheBuildToolIsChecked) {
  // wrong_abi's own record says ABI 999; fba-plugin-manifest copied it into the manifest.
  fba::Registry r;
  const auto why = refusal(bad("wrong_abi"), r);
  EXPECT_NE(why.find("was built for fba plugin ABI 999 (fba 9.9.9)"), std::string::npos) << why;
}

TEST(Plugin, ASharedObjectWithoutAManifestIsRefusedAndNotRun) {
  const fs::path dir = temp_dir();
  const fs::path so = copy_plugin(bad("static_marker"), dir);
  fs::remove(fba::detail::manifest_path(so));
  const fs::path marker = dir / "marker";
  MarkerEnv env(marker);
  fba::Registry r;
  const auto why = refusal(so.string(), r);
  EXPECT_NE(why.find("has no manifest static_marker.manifest.json"), std::string::npos) << why;
  EXPECT_FALSE(fs::exists(marker));
}

TEST(Plugin, AStaleManifestIsRefused) {
  const fs::path dir = temp_dir();
  const fs::path so = copy_plugin(bad("static_marker"), dir);
  edit_manifest(so, [](auto& m) { m.build_id = "0123"; });
  fba::Registry r;
  const auto why = refusal(so.string(), r);
  EXPECT_NE(why.find("describes another build of it (build id 0123"), std::string::npos) << why;
}

TEST(Plugin, AManifestThatIsNoJsonSaysWhere) {
  const fs::path dir = temp_dir();
  const fs::path so = copy_plugin(bad("static_marker"), dir);
  std::ofstream(fba::detail::manifest_path(so)) << "{ \"fba_plugin_manifest\": 1, ";
  fba::Registry r;
  const auto why = refusal(so.string(), r);
  EXPECT_NE(why.find("static_marker.manifest.json is not valid JSON"), std::string::npos) << why;
}

TEST(Plugin, ASharedObjectWithoutTheRecordIsRefused) {
  const fs::path so = copy_plugin(bad("no_symbol"), temp_dir());
  write_manifest(so);
  fba::Registry r;
  ASSERT_EQ(r.load_path({so.parent_path()}).size(), 0u);  // its manifest is fine; its code is not run yet
  try {
    r.find("test.no_symbol");
    FAIL() << "no error";
  } catch (const fba::PluginError& e) {
    EXPECT_NE(e.reason().find("is not an fba plugin: the symbol 'fba_plugin_info' is missing"), std::string::npos) << e.reason();
    EXPECT_NE(e.reason().find("it provides component type 'test.no_symbol'"), std::string::npos) << e.reason();
  }
}

TEST(Plugin, AnUndefinedReferenceIsNamed) {
  const fs::path so = copy_plugin(bad("undefined_reference"), temp_dir());
  write_manifest(so);
  fba::Registry r;
  const auto why = refusal(so.string(), r);
  EXPECT_NE(why.find("cannot be loaded"), std::string::npos) << why;
  EXPECT_NE(why.find("fba_test_function_nobody_defines"), std::string::npos) << why;
}

TEST(Plugin, ATypeRegisteredTwiceNamesBothFiles) {
  fba::Registry r;
  r.load_plugin(examples());
  const auto why = refusal(bad("duplicate_type"), r);
  EXPECT_NE(why.find("registers component type 'examples.counter', which " + examples() + " registered already"), std::string::npos) << why;
  EXPECT_EQ(r.find("examples.counter")->origin, examples());  // the first one stays
}

TEST(Plugin, APluginWithoutComponentsIsRefused) {
  const fs::path so = copy_plugin(bad("no_components"), temp_dir());
  write_manifest(so);
  fba::Registry r;
  EXPECT_NE(refusal(so.string(), r).find("registers no component types"), std::string::npos);
}

TEST(Plugin, AFileThatIsNoSharedObjectIsRefused) {
  const fs::path dir = temp_dir();
  fba::Registry r;
  std::ofstream(dir / "garbage.so") << "this is not ELF";
  EXPECT_NE(refusal((dir / "garbage.so").string(), r).find("is not an ELF shared object"), std::string::npos);
  EXPECT_NE(refusal((dir / "missing.so").string(), r).find("no such file"), std::string::npos);
}

TEST(Plugin, OddFilesOnThePluginPathSayWhatTheyAre) {
  const fs::path dir = temp_dir();
  fs::create_directory(dir / "x.so");
  std::ofstream(dir / "empty.so").close();
  fs::create_symlink(dir / "nowhere.so", dir / "dangling.so");
  fs::create_symlink(dir / "loop_b.so", dir / "loop_a.so");
  fs::create_symlink(dir / "loop_a.so", dir / "loop_b.so");
  {
    // The first 1000 bytes of a real plugin: a copy that was cut short.
    std::ifstream in(bad("static_marker"), std::ios::binary);
    std::string head(1000, '\0');
    in.read(head.data(), 1000);
    std::ofstream(dir / "truncated.so", std::ios::binary) << head;
  }
  fba::Registry r;
  std::map<std::string, std::string> why;
  for (const auto& e : r.load_path({dir})) why[fs::path(e.file()).filename().string()] = e.reason();
  EXPECT_NE(why["x.so"].find("is a directory, not a plugin file"), std::string::npos) << why["x.so"];
  EXPECT_NE(why["empty.so"].find("is an empty file (0 bytes)"), std::string::npos) << why["empty.so"];
  EXPECT_NE(why["dangling.so"].find("is a dangling symbolic link to"), std::string::npos) << why["dangling.so"];
  EXPECT_NE(why["loop_a.so"].find("symbolic link that loops"), std::string::npos) << why["loop_a.so"];
  EXPECT_NE(why["truncated.so"].find("is truncated"), std::string::npos) << why["truncated.so"];
}

TEST(Plugin, APluginForAnotherArchitectureSaysWhich) {
  const fs::path dir = temp_dir();
  std::string bytes;
  {
    std::ifstream in(bad("static_marker"), std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const std::uint16_t aarch64 = 183;  // EM_AARCH64, at offset 18 of the ELF header (little-endian here)
  bytes[18] = static_cast<char>(aarch64 & 0xff);
  bytes[19] = static_cast<char>(aarch64 >> 8);
  std::ofstream(dir / "arm.so", std::ios::binary) << bytes;
  fba::Registry r;
  const auto why = refusal((dir / "arm.so").string(), r);
  EXPECT_NE(why.find("was built for aarch64; this fba runs on x86-64"), std::string::npos) << why;

  // A 32-bit plugin's header is shorter, but its machine is at the same place: named too.
  bytes[4] = 1;  // EI_CLASS: ELFCLASS32
  const std::uint16_t i386 = 3;  // EM_386
  bytes[18] = static_cast<char>(i386);
  bytes[19] = 0;
  std::ofstream(dir / "i386.so", std::ios::binary) << bytes;
  const auto why32 = refusal((dir / "i386.so").string(), r);
  EXPECT_NE(why32.find("is a 32-bit ELF file, built for x86 (32-bit); this fba is a 64-bit program for x86-64"), std::string::npos)
      << why32;
}

TEST(Plugin, LoadPathReportsEveryFailureAndKeepsTheGoodOnes) {
  fba::Registry r;
  const auto errors = r.load_path({fba::test::plugin_dir(), fba::test::binary_dir() + "/core/tests/bad_plugins"});
  EXPECT_GE(errors.size(), 5u);
  EXPECT_NE(r.find("examples.passthrough"), nullptr);
}

TEST(Plugin, ABrokenPluginFailsOnlyTheTasksThatNeedIt) {
  const fs::path dir = temp_dir();
  const fs::path so = copy_plugin(bad("static_marker"), dir);
  edit_manifest(so, [](auto& m) { m.abi_version = 999; });
  fba::Registry r;
  EXPECT_EQ(r.load_path({fba::test::plugin_dir(), dir}).size(), 1u);
  const auto ok = fba::load_task_text("components:\n  c: { type: examples.counter, params: { count: 3 } }\n", "t.yaml", ".", r);
  EXPECT_EQ(ok.components.size(), 1u);
  try {
    fba::load_task_text("components:\n  m: { type: test.marker }\n", "t.yaml", ".", r);
    FAIL() << "a task using the broken plugin was accepted";
  } catch (const fba::PluginError& e) {
    EXPECT_EQ(e.file(), so.string());
    EXPECT_NE(e.reason().find("ABI 999"), std::string::npos) << e.reason();
  }
}

TEST(Plugin, CheckingATaskMapsOnlyThePluginsItUses) {
  // A plugin folder of its own: the examples, and two plugins the task does not use.
  const fs::path dir = temp_dir();
  copy_plugin(examples(), dir);
  copy_plugin(bad("static_marker"), dir);
  copy_plugin(bad("blob_large"), dir);
  fba::Registry r;
  EXPECT_TRUE(r.load_path({dir}).empty());
  EXPECT_EQ(r.plugins().size(), 3u);
  EXPECT_EQ(mapped_plugins(dir), std::set<std::string>{});
  fba::load_task(fs::path(fba::test::tasks_dir()) / "examples/chain.yaml", r);
  EXPECT_EQ(mapped_plugins(dir), std::set<std::string>{"fba-examples.so"});
}

// A composite file on the plugin path whose inner component comes from the marker plugin.
void write_marker_composite(const fs::path& dir) {
  std::ofstream(dir / "marker_source.yaml") << "composite: test.marker_source\n"
                                               "outputs:\n  out: m.out\n"
                                               "components:\n  m: { type: test.marker }\n";
}

TEST(Plugin, CheckingACompositeTaskMapsOnlyThePluginsItsComponentsUse) {
  // The examples with their shipped composite (examples.relay, used by the task), and a composite
  // whose inner type comes from a plugin the task does not use: that plugin's code never runs.
  const fs::path dir = temp_dir();
  copy_plugin(examples(), dir);
  fs::copy_file(fs::path(fba::test::plugin_dir()) / "relay.yaml", dir / "relay.yaml");
  copy_plugin(bad("static_marker"), dir);
  write_marker_composite(dir);
  const fs::path marker = dir / "marker";
  MarkerEnv env(marker);
  fba::Registry r;
  EXPECT_TRUE(r.load_path({dir}).empty());
  EXPECT_EQ(mapped_plugins(dir), std::set<std::string>{}) << "reading the path ran plugin code";
  const auto task = fba::load_task(fs::path(fba::test::tasks_dir()) / "examples/composite.yaml", r);
  EXPECT_EQ(task.components.size(), 8u);  // the relays' passthroughs, expanded
  EXPECT_EQ(mapped_plugins(dir), std::set<std::string>{"fba-examples.so"});
  EXPECT_FALSE(fs::exists(marker)) << "a plugin that only an unused composite needs was loaded";
  // The counterpart: a task that uses the composite loads its plugin.
  fba::load_task_text("components:\n  s: { type: test.marker_source }\n", "t.yaml", dir, r);
  EXPECT_TRUE(fs::exists(marker));
}

TEST(Plugin, ACompositeOverABrokenPluginFailsOnlyTheTasksThatUseIt) {
  const fs::path dir = temp_dir();
  const fs::path so = copy_plugin(bad("static_marker"), dir);
  edit_manifest(so, [](auto& m) { m.abi_version = 999; });
  write_marker_composite(dir);
  fba::Registry r;
  const auto errors = r.load_path({fba::test::plugin_dir(), dir});
  ASSERT_EQ(errors.size(), 1u);  // the plugin; the composite is not read until a task uses it
  EXPECT_EQ(errors[0].file(), so.string());
  EXPECT_EQ(fba::load_task(fs::path(fba::test::tasks_dir()) / "examples/composite.yaml", r).components.size(), 8u);
  try {
    fba::load_task_text("components:\n  s: { type: test.marker_source }\n", "t.yaml", dir, r);
    FAIL() << "a task using a composite over the broken plugin was accepted";
  } catch (const fba::PluginError& e) {
    EXPECT_EQ(e.file(), (dir / "marker_source.yaml").string());
    EXPECT_NE(e.reason().find(so.string()), std::string::npos) << e.reason();
    EXPECT_NE(e.reason().find("ABI 999"), std::string::npos) << e.reason();
  }
}

TEST(Plugin, CompositesOnThePathThatUseEachOtherInACycleAreRefusedWhenUsed) {
  const fs::path dir = temp_dir();
  std::ofstream(dir / "a.yaml") << "composite: test.a\noutputs:\n  out: b.out\ncomponents:\n  b: { type: test.b }\n";
  std::ofstream(dir / "b.yaml") << "composite: test.b\noutputs:\n  out: a.out\ncomponents:\n  a: { type: test.a }\n";
  fba::Registry r;
  EXPECT_TRUE(r.load_path({dir}).empty());
  try {
    r.find("test.a");
    FAIL() << "a cycle of composites was accepted";
  } catch (const fba::PluginError& e) {
    EXPECT_NE(e.reason().find("contains itself"), std::string::npos) << e.reason();
  }
}

TEST(Plugin, TwoLayoutsOfOneDataTypeAreRefusedNamingBothPlugins) {
  const fs::path dir = temp_dir();
  const fs::path large = copy_plugin(bad("blob_large"), dir);
  const fs::path small = copy_plugin(bad("blob_small"), dir);  // sorted after blob_large: refused
  fba::Registry r;
  const auto errors = r.load_path({dir});
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0].file(), small.string());
  const auto& why = errors[0].reason();
  EXPECT_NE(why.find("uses data type 'test.Blob' with size 8, alignment 8, version 1, but " + large.string() +
                     " uses it with size 16, alignment 8, version 1"),
            std::string::npos) << why;
  // A task that uses the first one still loads; one that uses the other is refused.
  EXPECT_NO_THROW(fba::load_task_text("components:\n  b: { type: test.blob_large }\n", "t.yaml", ".", r));
  EXPECT_THROW(fba::load_task_text("components:\n  b: { type: test.blob_small }\n", "t.yaml", ".", r), fba::PluginError);
}

TEST(Plugin, ADataTypeRegisteredWithAnotherLayoutIsAnErrorNamingBoth) {
  fba::register_type("test.Twice", "doc", fba::TypeLayout{8, 8, 1});
  try {
    fba::TypeOriginScope origin("second.so");
    fba::register_type("test.Twice", "doc", fba::TypeLayout{8, 8, 2});
    FAIL() << "no error";
  } catch (const std::logic_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("size 8, alignment 8, version 1 in the program"), std::string::npos) << what;
    EXPECT_NE(what.find("size 8, alignment 8, version 2 in second.so"), std::string::npos) << what;
  }
}

TEST(Plugin, EveryDataTypeHasItsLayout) {
  const fba::TypeInfo* t = fba::type_of<std::int64_t>();
  EXPECT_EQ(t->layout, (fba::TypeLayout{8, 8, 1}));
  EXPECT_EQ(t->header, "fba/packet.hpp");
}

TEST(Plugin, TheManifestDescribesEveryTypeAndItsDataTypes) {
  const auto m = fba::detail::read_manifest(fba::detail::manifest_path(examples()));
  EXPECT_EQ(m.name, "examples");
  EXPECT_EQ(m.abi_version, fba::kAbiVersion);
  EXPECT_EQ(m.build_id, fba::detail::check_elf(examples()).build_id);
  EXPECT_FALSE(m.build_id.empty());
  fba::Registry r;
  r.load_plugin(examples());
  for (const auto& t : m.types) EXPECT_EQ(t.interface, fba::detail::spec_json(r.find(t.name)->spec)) << t.name;
  bool has_int = false;
  for (const auto& d : m.data_types) has_int |= d.name == "fba.Int" && d.layout == fba::TypeLayout{8, 8, 1};
  EXPECT_TRUE(has_int);
}

TEST(Plugin, TheLibraryStaysLoadedWhileAComponentFromItLives) {
  std::unique_ptr<fba::Task> task;
  {
    fba::Registry r;
    r.load_plugin(examples());
    const auto cfg = fba::load_task_text("components:\n  c: { type: examples.counter, params: { count: 3 } }\n", "t.yaml", ".", r);
    task = std::make_unique<fba::Task>(cfg);
  }  // the registry is gone; the task's components still hold the library
  EXPECT_NE(dlopen(examples().c_str(), RTLD_NOW | RTLD_NOLOAD), nullptr);
  const auto result = task->run();
  EXPECT_EQ(result.outcome, fba::Outcome::Success) << result.reason;
}
