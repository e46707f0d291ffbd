// fba-evaluate's command line: every argument is checked as fba-run checks parameters (a value out
// of range, NaN, inverted bounds or an option that would be ignored is refused with exit status 2
// and a message naming it), and negative numbers are values, not options.
#include <sys/stat.h>

#include <cstring>
#include <ostream>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "fba/geometry/mesh_io.hpp"
#include "fba/geometry/renderer.hpp"
#include "fba/geometry/viewpoints.hpp"
#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"
#include "support/child_process.hpp"
#include "support/data_sets.hpp"

namespace {

using fba::test::Result;

Result fba_evaluate(std::vector<std::string> args) {
  args.insert(args.begin(), fba::test::program("fba-evaluate"));
  return fba::test::run(std::move(args));
}

const std::string kBanana = fba::test::ycb_mesh("YcbBanana");
const std::string kDinoSet = fba::test::kDinoPar;
const std::string kDinoTask = fba::test::source_dir() + "/tasks/carve_dino.yaml";

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// The run is refused with exit status 2 and a message that contains `says`.
void expect_refused(const std::vector<std::string>& args, const std::string& says) {
  const Result r = fba_evaluate(args);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(says), std::string::npos) << "expected \"" << says << "\" in:\n" << r.output;
}

// One bad argument of a subcommand: the words after the subcommand's valid start, and what the
// refusal must say.
struct BadArgument {
  std::string name;  // the test's name
  std::vector<std::string> args;
  std::string says;
};

void PrintTo(const BadArgument& b, std::ostream* os) { *os << b.name; }

std::vector<std::string> synthetic(std::initializer_list<std::string> extra) {
  std::vector<std::string> a{"synthetic", "--mesh", kBanana};
  a.insert(a.end(), extra);
  return a;
}

std::vector<std::string> model(std::initializer_list<std::string> extra) {
  std::vector<std::string> a{"model", "--model", kBanana};
  a.insert(a.end(), extra);
  return a;
}

std::vector<std::string> grasp(std::initializer_list<std::string> extra) {
  std::vector<std::string> a{"grasp", "--mesh", kBanana};
  a.insert(a.end(), extra);
  return a;
}

// The list need not exist: the command line is checked before the list is read.
std::vector<std::string> grasp_batch(std::initializer_list<std::string> extra) {
  std::vector<std::string> a{"grasp", "--batch", "no-such-list.yaml"};
  a.insert(a.end(), extra);
  return a;
}

class EvaluateCliRefuses : public ::testing::TestWithParam<BadArgument> {};

// Every bad value is refused before any work, with exit status 2 and a message naming the option,
// what it expects and what was found.
TEST_P(EvaluateCliRefuses, TheBadArgumentWithStatusTwoAndItsName) { expect_refused(GetParam().args, GetParam().says); }

std::string test_name(const ::testing::TestParamInfo<BadArgument>& info) { return info.param.name; }

INSTANTIATE_TEST_SUITE_P(Synthetic, EvaluateCliRefuses, ::testing::Values(
    BadArgument{"ViewsZero", synthetic({"--views", "0"}), "--views must be in [1, 1000]; found 0"},
    BadArgument{"ViewsNegative", synthetic({"--views", "-3"}), "--views must be in [1, 1000]; found -3"},
    BadArgument{"ViewsNotAnInteger", synthetic({"--views", "2.5"}), "--views must be an integer in [1, 1000]; found '2.5'"},
    BadArgument{"ViewsText", synthetic({"--views", "many"}), "--views must be an integer in [1, 1000]; found 'many'"},
    BadArgument{"ViewsHuge", synthetic({"--views", "99999999999999999999"}), "--views must be an integer in [1, 1000]; found '99999999999999999999'"},
    BadArgument{"MinElevationNaN", synthetic({"--min-elevation", "nan"}), "--min-elevation must be in [-90, 90]; found nan"},
    BadArgument{"MaxElevationNaN", synthetic({"--max-elevation", "nan"}), "--max-elevation must be in [-90, 90]; found nan"},
    BadArgument{"ElevationsInverted", synthetic({"--min-elevation", "60", "--max-elevation", "30"}), "--max-elevation must be in [60, 90]; found 30"},
    BadArgument{"ElevationText", synthetic({"--min-elevation", "low"}), "--min-elevation must be a number in [-90, 90]; found 'low'"},
    BadArgument{"ThreadsNegative", synthetic({"--threads", "-1"}), "--threads must be in [0, 256]; found -1"},
    BadArgument{"ThreadsTooMany", synthetic({"--threads", "257"}), "--threads must be in [0, 256]; found 257"},
    BadArgument{"DepthTooDeep", synthetic({"--depth", "19"}), "--depth must be in [1, 10]; found 19"},
    BadArgument{"DepthZero", synthetic({"--depth", "0"}), "--depth must be in [1, 10]; found 0"},
    BadArgument{"MarginNegative", synthetic({"--margin", "-0.1"}), "--margin must be in [0, 10]; found -0.1"},
    BadArgument{"MarginInfinite", synthetic({"--margin", "inf"}), "--margin must be in [0, 10]; found inf"},
    BadArgument{"MinElevationMinusInfinity", synthetic({"--min-elevation", "-inf"}), "--min-elevation must be in [-90, 90]; found -inf"},
    BadArgument{"ToleranceInfinite", synthetic({"--tolerance", "inf"}), "--tolerance must be in [0, 1000]; found inf"},
    BadArgument{"UnknownShortOption", synthetic({"-x"}), "unrecognised option '-x'"},
    BadArgument{"NoMesh", {"synthetic", "--views", "8"}, "the option '--mesh' is required"}), test_name);

INSTANTIATE_TEST_SUITE_P(Model, EvaluateCliRefuses, ::testing::Values(
    BadArgument{"DepthZero", model({"--mesh", kBanana, "--depth", "0"}), "--depth must be in [1, 10]; found 0"},
    BadArgument{"DepthTooDeepWithImages", model({"--images", kDinoSet, "--depth", "30"}), "--depth must be in [1, 10]; found 30"},
    BadArgument{"DepthText", model({"--mesh", kBanana, "--depth", "six"}), "--depth must be an integer in [1, 10]; found 'six'"},
    BadArgument{"MarginNaN", model({"--mesh", kBanana, "--margin", "nan"}), "--margin must be in [0, 10]; found nan"},
    BadArgument{"BoundsInverted", model({"--mesh", kBanana, "--bounds", "0.1", "-0.1", "-0.1", "-0.1", "0.1", "0.1"}),
                "--bounds: xmin must be below xmax; found 0.1 and -0.1"},
    BadArgument{"BoundsNaN", model({"--mesh", kBanana, "--bounds", "-0.1", "-0.1", "nan", "0.1", "0.1", "0.1"}),
                "--bounds needs finite numbers (xmin ymin zmin xmax ymax zmax); number 3 is nan"},
    BadArgument{"BoundsIncomplete", model({"--mesh", kBanana, "--bounds", "-0.1", "-0.1", "-0.1"}),
                "--bounds needs 6 numbers (xmin ymin zmin xmax ymax zmax); found 3"},
    BadArgument{"BoundsInvertedWithImages", model({"--images", kDinoSet, "--bounds", "0.1", "0.1", "0.1", "-0.1", "-0.1", "-0.1"}),
                "--bounds: xmin must be below xmax"},
    BadArgument{"BoundsWithoutAMesh", model({"--images", kDinoSet, "--bounds", "-0.1", "-0.1", "-0.1", "0.1", "0.1", "0.1"}),
                "--bounds applies to the comparison with a mesh"},
    BadArgument{"DepthWithoutAMesh", model({"--images", kDinoSet, "--depth", "7"}), "--depth applies to the comparison with a mesh"},
    BadArgument{"SetWithoutATask", model({"--images", kDinoSet, "--set", "contours.threshold=0.3"}), "--set applies to the task given with --task"},
    BadArgument{"UnknownOption", model({"--mesh", kBanana, "--bogus", "1"}), "unrecognised option '--bogus'"}), test_name);

INSTANTIATE_TEST_SUITE_P(Grasp, EvaluateCliRefuses, ::testing::Values(
    BadArgument{"RandomNegative", grasp({"--random", "-1"}), "--random must be an integer in [0, 1000000]; found '-1'"},
    BadArgument{"RandomTooMany", grasp({"--random", "1000001"}), "--random must be in [0, 1000000]; found 1000001"},
    BadArgument{"SeedNegative", grasp({"--seed", "-5"}), "--seed must be an integer in [0, 18446744073709551615]; found '-5'"},
    BadArgument{"SamplesTooFew", grasp({"--synthesise", "--samples", "2"}), "--samples must be in [3, 1000000]; found 2"},
    BadArgument{"SamplesWithoutSynthesis", grasp({"--random", "10", "--samples", "50"}), "--samples applies to --synthesise"},
    BadArgument{"FrictionNaN", grasp({"--random", "10", "--friction", "nan"}), "--friction must be in [0, 10]; found nan"},
    BadArgument{"FrictionNegative", grasp({"--random", "10", "--friction", "-0.5"}), "--friction must be in [0, 10]; found -0.5"},
    BadArgument{"ConeEdgesTooFew", grasp({"--random", "10", "--cone-edges", "2"}), "--cone-edges must be in [3, 64]; found 2"},
    BadArgument{"MeshPoseIncomplete", grasp({"--random", "10", "--mesh-pose", "1", "2"}),
                "--mesh-pose needs 6 numbers (x y z roll pitch yaw, metres and radians); found 2"},
    BadArgument{"MeshPoseNaN", grasp({"--random", "10", "--mesh-pose", "0", "0", "0", "-1.5", "nan", "0"}),
                "--mesh-pose needs finite numbers (x y z roll pitch yaw, metres and radians); number 5 is nan"},
    BadArgument{"NothingToEvaluate", grasp({"--random", "0"}), "nothing to evaluate"}), test_name);

INSTANTIATE_TEST_SUITE_P(GraspBatch, EvaluateCliRefuses, ::testing::Values(
    BadArgument{"JobsZero", grasp_batch({"--jobs", "0"}), "--jobs must be in [1, 64]; found 0"},
    BadArgument{"JobsShortOptionTooMany", grasp_batch({"-j", "65"}), "--jobs must be in [1, 64]; found 65"},
    BadArgument{"JobsAttachedText", grasp_batch({"-jx"}), "--jobs must be an integer in [1, 64]; found 'x'"},
    BadArgument{"RandomNegative", grasp_batch({"--random", "-1"}), "--random must be an integer in [0, 1000000]; found '-1'"},
    BadArgument{"SeedText", grasp_batch({"--seed", "one"}), "--seed must be an integer in [0, 18446744073709551615]; found 'one'"},
    BadArgument{"FbaRunMissing", grasp_batch({"--fba-run", "/no/such/fba-run"}),
                "--fba-run: expected an executable program; found '/no/such/fba-run'"},
    BadArgument{"FbaRunNotOnPath", grasp_batch({"--fba-run", "no-such-fba-run-program"}),
                "--fba-run: expected an executable program; found 'no-such-fba-run-program'"},
    BadArgument{"OutputAFile", grasp_batch({"-o", kBanana}), "--output: expected a folder; found '" + kBanana + "'"},
    BadArgument{"UnknownShortOption", grasp_batch({"-q"}), "unrecognised option '-q'"}), test_name);

// The banana compared with itself inside a box given with negative corners: a negative number is a
// value of --bounds, and the run succeeds.
TEST(EvaluateCli, NegativeNumbersAreOptionValues) {
  const Result r = fba_evaluate(model({"--mesh", kBanana, "--depth", "4", "--bounds", "-0.2", "-0.2", "-0.2", "0.2", "0.2", "0.2"}));
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("(a) vs"), std::string::npos) << r.output;
  EXPECT_EQ(fba_evaluate({"model", "-h"}).status, 0);
}

// With --task, the silhouettes are the task's: its contour component with its parameters (and
// --set overrides) on its image set. A minimum area no view reaches leaves every view without one,
// which fba's default extraction would not.
TEST(EvaluateCli, ModelWithTaskMakesSilhouettesWithTheTasksContourSettings) {
  const Result defaults = fba_evaluate(model({"--images", kDinoSet}));
  EXPECT_EQ(defaults.status, 0) << defaults.output;
  EXPECT_EQ(count(defaults.output, "no silhouette"), 0u) << defaults.output;
  EXPECT_NE(defaults.output.find("over 15 views"), std::string::npos) << defaults.output;

  const Result task = fba_evaluate(model({"--task", kDinoTask, "--set", "contours.min_area=1e9"}));
  EXPECT_EQ(task.status, 0) << task.output;
  EXPECT_NE(task.output.find("by the task's component 'contours'"), std::string::npos) << task.output;
  EXPECT_EQ(count(task.output, "no silhouette (dinoSR"), 15u) << task.output;  // the good views of the task's set
  EXPECT_EQ(task.output.find("reprojection IoU:"), std::string::npos) << task.output;

  const Result as_is = fba_evaluate(model({"--task", kDinoTask, "--set", "views.limit=3"}));
  EXPECT_EQ(as_is.status, 0) << as_is.output;
  EXPECT_NE(as_is.output.find("over 3 views"), std::string::npos) << as_is.output;
}

TEST(EvaluateCli, ModelRefusesATaskWithoutContourExtractionOrASetWithoutATask) {
  expect_refused(model({"--task", fba::test::source_dir() + "/tasks/examples/chain.yaml"}),
                 "has no vision.contour_extraction component");
  expect_refused(model({"--images", kDinoSet, "--set", "contours.threshold=0.3"}), "--set applies to the task given with --task");
  expect_refused(model({"--task", kDinoTask, "--set", "contours.threshold=7"}), "the task file does not load");
}

// A valid binary PLY whose data starts with the byte 0x0A (as the carver could write): assimp 5.2.5
// crashed on it; it is read and compared.
TEST(EvaluateCli, ModelPlyWhoseDataStartsWithANewlineByteIsRead) {
  const fba::test::TempDir dir;
  const float lo = [] {
    float x = -0.05f;
    unsigned char b[4];
    std::memcpy(b, &x, 4);
    b[0] = 0x0A;
    std::memcpy(&x, b, 4);
    return x;
  }();
  const float hi = 0.05f;
  std::string bytes = "ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
                      "property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < 8; ++i) {
    const float v[3] = {(i & 1) ? hi : lo, (i & 2) ? hi : -0.05f, (i & 4) ? hi : -0.05f};
    bytes.append(reinterpret_cast<const char*>(v), 12);
  }
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    const int t[2][3] = {{q[0], q[1], q[2]}, {q[0], q[2], q[3]}};
    for (const auto& tri : t) {
      bytes.push_back(3);
      bytes.append(reinterpret_cast<const char*>(tri), 12);
    }
  }
  const std::string path = dir.file("box.ply");
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  const Result r = fba_evaluate({"model", "--model", path, "--mesh", path, "--depth", "4"});
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("12 triangles"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("IoU 1.0000"), std::string::npos) << r.output;
}

// An fba image set with the provider's own masks: the model is scored against them, not against
// silhouettes fba extracts (here there would be none: the image is black). The mask is the
// model's own render, so the score is exactly 1.
TEST(EvaluateCli, ModelImagesWithTheSetsOwnMasksAreScoredAgainstThem) {
  const fba::test::TempDir dir;
  const fba::TriangleMesh box = fba::geometry::make_box({-0.2, -0.15, -0.05}, {0.2, 0.15, 0.05});
  fba::geometry::write_ply(box, dir.file("box.ply"));
  fba::CameraModel camera = fba::geometry::make_camera(64, 48, 50, 50, 31.5, 23.5);
  camera.camera_from_world = Eigen::Translation3d(0, 0, 1) * Eigen::Isometry3d::Identity();
  ASSERT_TRUE(cv::imwrite(dir.file("view.png"), cv::Mat(48, 64, CV_8UC1, cv::Scalar(0))));
  ASSERT_TRUE(cv::imwrite(dir.file("mask.png"), fba::geometry::render(box, camera).mask));
  const std::string set = dir.file("set.yaml",
                                   "%YAML:1.0\n---\nK: [50, 0, 31.5, 0, 50, 23.5, 0, 0, 1]\nimages:\n"
                                   "  - { path: view.png, mask: mask.png, R: [1,0,0,0,1,0,0,0,1], t: [0, 0, 1] }\n");
  const Result r = fba_evaluate({"model", "--model", dir.file("box.ply"), "--images", set});
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("by the set's own masks"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("reprojection IoU: min 1.0000  mean 1.0000  over 1 views"), std::string::npos) << r.output;
}

// The grasp measure needs the solid's volume and centre of mass, which an open surface does not
// have: a mesh that is not closed is refused, with how many edges are of one triangle only.
TEST(EvaluateCli, GraspRefusesAMeshThatIsNotClosed) {
  const fba::test::TempDir dir;
  fba::TriangleMesh open = fba::geometry::make_box({-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05});
  open.triangles.resize(open.triangles.size() - 2);  // a face of the box left open: its four edges
  const std::string path = dir.file("open.ply");
  fba::geometry::write_ply(open, path);
  const std::string says = "mesh '" + path + "': expected a closed surface (what is measured is inside it: the volume and centre of "
                           "mass of a grasp's object, the voxels of a model's truth); found 4 boundary edges";
  // Before any work: no row for the banana, which is closed, before the open mesh is refused.
  const Result r = fba_evaluate({"grasp", "--mesh", kBanana, path, "--random", "10"});
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(says), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("YcbBanana"), std::string::npos) << r.output;
  expect_refused({"grasp", "--mesh", path, "--synthesise", "--samples", "100"}, says);
  const std::string summary = dir.file("summary.json", R"({"grasp": {"contacts": [
      {"position": [-0.05, 0, 0], "normal": [1, 0, 0]}, {"position": [0.05, 0.02, 0], "normal": [-1, 0, 0]},
      {"position": [0.05, -0.02, 0], "normal": [-1, 0, 0]}]}})");
  expect_refused({"grasp", "--mesh", path, "--summary", summary}, says);
  // The model comparison and the synthetic carve voxelise the true solid: the same refusal.
  expect_refused({"synthetic", "--mesh", path, "--views", "2", "--depth", "3"}, says);
  const std::string model = dir.file("model.ply");
  fba::geometry::write_ply(fba::geometry::make_box({-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05}), model);
  expect_refused({"model", "--model", model, "--mesh", path, "--depth", "3"}, says);
}

// Opening a FIFO for reading waits for a writer, maybe forever: --summary must be a regular file.
TEST(EvaluateCli, GraspRefusesASummaryThatIsNotARegularFile) {
  const fba::test::TempDir dir;
  const std::string fifo = dir.file("summary.fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  fba::test::Child evaluate({fba::test::program("fba-evaluate"), "grasp", "--mesh", kBanana, "--summary", fifo});
  const int status = evaluate.wait(0);  // -1: it hung
  const std::string output = evaluate.read_until("");
  EXPECT_EQ(status, 2) << output;
  EXPECT_NE(output.find("--summary: expected a regular file; '" + fifo + "' is a FIFO"), std::string::npos) << output;
  expect_refused({"grasp", "--mesh", kBanana, "--summary", dir.path().string()}, "--summary: expected a regular file; '" +
                                                                                    dir.path().string() + "' is a folder");
}

}  // namespace
