// fba-evaluate families, run as a user runs it: the meshes it writes are closed and rest as they
// settled, the manifest says what each is, the batch list is one fba-evaluate grasp --batch reads,
// the same seed writes the same files, and a bad argument is refused naming what was expected.
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "support/child_process.hpp"
#include "support/geometry_checks.hpp"

namespace fba::geometry::test {
namespace {

namespace fs = std::filesystem;

std::string quoted(const std::string& s) { return "'" + s + "'"; }

fba::test::Result families(const std::string& args) {
  return fba::test::run_shell(quoted(fba::test::program("fba-evaluate")) + " families " + args);
}

std::string task() { return quoted(fba::test::tasks_dir() + "/grasp.yaml"); }

std::string text_of(const fs::path& p) {
  std::stringstream ss;
  ss << std::ifstream(p).rdbuf();
  return ss.str();
}

std::size_t lines(const std::string& s) { return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n')); }

// The batch's dry run over the list: each run's fba-run command line.
fba::test::Result dry_run(const fs::path& list) {
  return fba::test::run_shell(quoted(fba::test::program("fba-evaluate")) + " grasp --batch " + quoted(list.string()) +
                                " --dry-run --fba-run /bin/true");
}

TEST(FamiliesCli, WritesClosedMeshesAManifestAndAListTheBatchReads) {
  const TempDir dir;
  const fs::path out = dir.path() / "set";
  const auto r = families("--seed 7 --per-family 2 --poses 2 --families box,ring -o " + quoted(out.string()) + " --task " + task());
  ASSERT_EQ(r.status, 0) << r.output;
  const auto manifest = nlohmann::json::parse(text_of(out / "manifest.json"));
  EXPECT_EQ(manifest["seed"], 7);
  ASSERT_EQ(manifest["objects"].size(), 4u);
  std::map<std::string, int> per_family;
  for (const auto& o : manifest["objects"]) {
    SCOPED_TRACE(o["name"].get<std::string>());
    ++per_family[o["family"]];
    EXPECT_FALSE(o["parameters"].empty());
    const TriangleMesh mesh = load_mesh(out / o["file"].get<std::string>());
    EXPECT_EQ(closed_surface_fault(mesh), "");
    EXPECT_NEAR(signed_volume(mesh), o["volume_m3"].get<double>(), 1e-9);
    const Eigen::Vector3d size = mesh_bounds(mesh).sizes();  // a value: sizes() of a temporary box is an expression over it
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(size[k], o["size_m"][k].get<double>(), 1e-6);
    ASSERT_EQ(o["drops"].size(), 2u);
    for (const auto& rest : o["rests"]) {
      // The object turned as it rests, standing on the table: as closed, as large, lowest at z = 0.
      const TriangleMesh rested = load_mesh(out / rest["file"].get<std::string>());
      EXPECT_EQ(closed_surface_fault(rested), "");
      EXPECT_NEAR(signed_volume(rested), signed_volume(mesh), 1e-6 * signed_volume(mesh));
      EXPECT_NEAR(mesh_bounds(rested).min().z(), 0, 1e-7);
      EXPECT_FALSE(rest["drops"].empty());
    }
    for (const auto& d : o["drops"]) EXPECT_TRUE(d["still"].get<bool>());
  }
  EXPECT_EQ(per_family["box"], 2);
  EXPECT_EQ(per_family["ring"], 2);
  // One run per drop, the batch reads the list and makes them.
  const auto batch = dry_run(out / "families_random.yaml");
  ASSERT_EQ(batch.status, 0) << batch.output;
  EXPECT_EQ(lines(batch.output), 8u) << batch.output;
  EXPECT_NE(batch.output.find("scene.mesh=" + (out / "box" / "box-00-rest0.obj").string()), std::string::npos) << batch.output;
  EXPECT_NE(batch.output.find("scene.yaw="), std::string::npos);
}

TEST(FamiliesCli, TheSameSeedWritesTheSameFilesWhateverTheJobs) {
  const TempDir dir;
  const fs::path a = dir.path() / "a", b = dir.path() / "b";
  for (const auto& [out, jobs] : {std::pair{a, 1}, std::pair{b, 3}}) {
    const auto r = families("--seed 11 --per-family 2 --poses 2 --families tool,l_shape,ellipsoid --jobs " + std::to_string(jobs) + " -o " +
                            quoted(out.string()) + " --task " + task());
    ASSERT_EQ(r.status, 0) << r.output;
  }
  std::size_t files = 0;
  for (const auto& e : fs::recursive_directory_iterator(a)) {
    if (!e.is_regular_file()) continue;
    ++files;
    const fs::path other = b / fs::relative(e.path(), a);
    ASSERT_TRUE(fs::exists(other)) << other;
    EXPECT_EQ(text_of(e.path()), text_of(other)) << e.path();
  }
  EXPECT_GT(files, 2u + 6u);  // the manifest, the list, the six objects and their rests
}

TEST(FamiliesCli, WithYcbTheShippedMeshesJoinTheListAndVariantsCanBeCopied) {
  const TempDir dir;
  const fs::path out = dir.path() / "set";
  const auto r = families("--seed 3 --per-family 1 --poses 1 --families sphere --with-ycb --ycb-dir " + quoted(fba::test::data_dir() + "/ycb") +
                          " --variants-from " + quoted(fba::test::tasks_dir() + "/grasp_poses_random.yaml") + " -o " + quoted(out.string()) +
                          " --task " + task());
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string list = text_of(out / "families_random.yaml");
  for (const char* name : kYcbNames) EXPECT_NE(list.find(std::string(name) + "/model.obj"), std::string::npos) << name;
  const auto batch = dry_run(out / "families_random.yaml");
  ASSERT_EQ(batch.status, 0) << batch.output;
  EXPECT_EQ(lines(batch.output), 3u * 5u) << batch.output;  // loop, ring, uniform x (a sphere and four YCB meshes)
  EXPECT_NE(batch.output.find("planner.views=ring"), std::string::npos);
}

// Each refused with exit status 2 and a message naming the option, what it expects and what was found.
TEST(FamiliesCli, BadArgumentsAreRefusedNamingWhatWasExpected) {
  const TempDir dir;
  const std::string out = quoted((dir.path() / "new").string()), base = "--seed 1 --task " + task() + " ";
  fs::create_directories(dir.path() / "full");
  std::ofstream(dir.path() / "full" / "x") << "x";
  std::ofstream(dir.path() / "no-variants.yaml") << "task: grasp.yaml\n";
  const std::pair<std::string, std::string> cases[] = {
      {base + "--per-family 0 -o " + out, "--per-family must be in [1, 1000]; found 0"},
      {base + "--per-family ten -o " + out, "--per-family must be an integer in [1, 1000]; found 'ten'"},
      {"--seed -1 -o " + out, "--seed must be an integer in [0, 18446744073709551615]; found '-1'"},
      {"-o " + out + " --task " + task(), "--seed is required"},
      {base, "'--output' is required"},
      {base + "--poses 101 -o " + out, "--poses must be in [1, 100]; found 101"},
      {base + "--jobs 0 -o " + out, "--jobs must be in [1, 64]; found 0"},
      {base + "--families boxes -o " + out, "--families: unknown family 'boxes'; expected some of box, cylinder, sphere"},
      {base + "--families box,box -o " + out, "--families: 'box' is given twice"},
      {base + "-o " + quoted((dir.path() / "full").string()), "expected a new or empty folder (a set is not written over another); found"},
      {base + "-o " + quoted((dir.path() / "full" / "x").string()), "expected a folder to write the set into; found"},
      {base + "--ycb-dir data/ycb -o " + out, "--ycb-dir applies with --with-ycb"},
      {base + "--with-ycb --ycb-dir " + quoted((dir.path() / "none").string()) + " -o " + out,
       "--ycb-dir: expected the folder of the shipped YCB meshes"},
      {"--seed 1 --task " + quoted((dir.path() / "none.yaml").string()) + " -o " + out, "--task: expected the task file the list runs; found no file"},
      {base + "--variants-from " + quoted((dir.path() / "no-variants.yaml").string()) + " -o " + out, "to have a list 'variants'; found none"},
  };
  for (const auto& [args, says] : cases) {
    const auto r = families(args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(says), std::string::npos) << args << ": expected \"" << says << "\" in:\n" << r.output;
  }
  EXPECT_FALSE(fs::exists(dir.path() / "new"));  // nothing written by a refused command line
}

}  // namespace
}  // namespace fba::geometry::test
