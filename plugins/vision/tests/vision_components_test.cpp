// vision.* and sim.camera through the component harness, on the real data.
#include <gtest/gtest.h>

#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <fba/task_config.hpp>
#include <fba/testing.hpp>
#include <fba/types/frame.hpp>
#include <fba/types/octree.hpp>
#include <fba/types/pose.hpp>
#include <fba/types/silhouette.hpp>

#include "support/built_plugins.hpp"
#include "support/temp_dir.hpp"
#include "support/data_sets.hpp"
#include "support/events.hpp"

namespace fs = std::filesystem;
using fba::testing::ComponentHarness;

namespace {

using fba::test::built_plugins;
using fba::test::has_event;

using fba::test::kDinoPar;

}  // namespace

TEST(ImageSet, ServesTheGoodViewsInOrderWithTheirCalibration) {
  ComponentHarness h(built_plugins(), "vision.image_set", {{"file", kDinoPar}});
  EXPECT_EQ(h.run(), 15);
  EXPECT_TRUE(h.finished());
  const auto& frames = h.packets("frame");
  ASSERT_EQ(frames.size(), 15u);
  const auto& first = frames[0].get<fba::Frame>();
  EXPECT_EQ(first.image.cols, 640);
  EXPECT_NEAR(first.camera.K(0, 0), 3310.4, 1e-9);
  EXPECT_NEAR(first.camera.camera_from_world.translation().z(), 0.673097816109, 1e-12);
  for (const auto& p : frames) EXPECT_NE(fs::path(p.get<fba::Frame>().source).filename(), "dinoSR0006.png");
}

TEST(ImageSet, OnRequestServesTheNearestUnservedView) {
  ComponentHarness h(built_plugins(), "vision.image_set", {{"file", kDinoPar}, {"good_only", false}}, {"request"});
  EXPECT_EQ(h.run(), 0);  // nothing is served until asked
  ComponentHarness reference(built_plugins(), "vision.image_set", {{"file", kDinoPar}, {"good_only", false}});
  reference.run();
  const auto& all = reference.packets("frame");
  // Ask for exactly where view 9 was taken from, twice: view 9, then its nearest neighbour.
  const auto& nine = all[8].get<fba::Frame>();
  fba::Pose want;
  want.world_from_frame = nine.camera.camera_from_world.inverse();
  h.push<fba::Pose>("request", want);
  h.push<fba::Pose>("request", want);
  EXPECT_EQ(h.run(), 2);
  const auto& served = h.packets("frame");
  ASSERT_EQ(served.size(), 2u);
  EXPECT_EQ(served[0].get<fba::Frame>().index, 9);
  EXPECT_TRUE(served[1].get<fba::Frame>().index == 8 || served[1].get<fba::Frame>().index == 10)
      << served[1].get<fba::Frame>().index;
}

TEST(ImageSet, AMissingFileIsAConfigurationError) {
  EXPECT_THROW(ComponentHarness(built_plugins(), "vision.image_set", {{"file", "/nonexistent/set.txt"}}), fba::ConfigError);
}

// A real video file through OpenCV's VideoCapture, with a calibration file in OpenCV's own
// format and a pose input: every frame carries intrinsics, distortion and the pose.
TEST(Camera, CapturesAVideoFileWithCalibrationAndPose) {
  const fba::test::TempDir temp;
  const fs::path& dir = temp.path();
  const std::string video = (dir / "dino.avi").string();
  {
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 5, cv::Size(640, 480));
    ASSERT_TRUE(writer.isOpened());
    for (int i = 1; i <= 4; ++i) writer.write(cv::imread(fba::test::kDino + "/dinoSR000" + std::to_string(i) + ".png"));
  }
  const std::string calibration = (dir / "calibration.yaml").string();
  {
    cv::FileStorage fsw(calibration, cv::FileStorage::WRITE);
    fsw << "image_width" << 640 << "image_height" << 480;
    fsw << "camera_matrix" << (cv::Mat_<double>(3, 3) << 3310.4, 0, 316.73, 0, 3325.5, 200.55, 0, 0, 1);
    fsw << "distortion_coefficients" << (cv::Mat_<double>(1, 5) << 0.01, -0.002, 0, 0, 0);
  }
  // The file backend by name: 'any' also probes USB and FireWire cameras, which is slow and
  // leaks inside those libraries.
  ComponentHarness h(built_plugins(), "vision.camera",
                     {{"source", video}, {"backend", "ffmpeg"}, {"calibration", calibration}}, {"pose"});
  fba::Pose pose;
  pose.world_from_frame.translation() << 0.1, 0.2, 0.3;
  h.push<fba::Pose>("pose", pose);
  EXPECT_EQ(h.run(), 5);  // four frames, then the end of the file
  const auto& frames = h.packets("frame");
  ASSERT_EQ(frames.size(), 4u);
  for (const auto& p : frames) {
    const auto& f = p.get<fba::Frame>();
    EXPECT_EQ(f.image.size(), cv::Size(640, 480));
    EXPECT_NEAR(f.camera.K(1, 1), 3325.5, 1e-9);
    EXPECT_NEAR(f.camera.distortion.at<double>(0), 0.01, 1e-12);
    EXPECT_TRUE(f.has_pose);
    EXPECT_NEAR(f.camera.centre_in_world().y(), 0.2, 1e-12);
  }
  EXPECT_TRUE(h.finished());
  EXPECT_TRUE(has_event(h.events(), "lost"));
}

// A wrist camera in the view loop: a frame only for a pose received, as sim.camera renders one
// per pose; the frames read in between are dropped, so the next one shows the camera where the
// new pose says.
TEST(Camera, PerPoseCaptureGivesOneFramePerPoseReceived) {
  const fba::test::TempDir temp;
  const std::string video = (temp.path() / "grey.avi").string();
  {
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 5, cv::Size(64, 48));
    ASSERT_TRUE(writer.isOpened());
    for (int i = 0; i < 6; ++i) writer.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(40 * i)));
  }
  ComponentHarness h(built_plugins(), "vision.camera", {{"source", video}, {"backend", "ffmpeg"}, {"capture", "per_pose"}},
                     {"pose"});
  EXPECT_TRUE(h.step());  // a frame read, no pose yet: nothing sent
  EXPECT_TRUE(h.packets("frame").empty());
  fba::Pose pose;
  pose.world_from_frame.translation() << 0.1, 0.2, 0.3;
  h.push<fba::Pose>("pose", pose);
  EXPECT_TRUE(h.step());
  ASSERT_EQ(h.packets("frame").size(), 1u);
  const auto& f = h.packets("frame")[0].get<fba::Frame>();
  EXPECT_TRUE(f.has_pose);
  EXPECT_NEAR(f.camera.centre_in_world().z(), 0.3, 1e-12);
  EXPECT_NEAR(cv::mean(f.image)[0], 40, 8);  // the second frame of the file: the first was read before the pose
  EXPECT_TRUE(h.step());  // no new pose: the frame is read and dropped
  EXPECT_EQ(h.packets("frame").size(), 1u);
}

TEST(Camera, AnUnopenableSourceIsAConfigurationError) {
  EXPECT_THROW(ComponentHarness(built_plugins(), "vision.camera", {{"source", "/nonexistent/video.avi"}, {"backend", "ffmpeg"}}),
               fba::ConfigError);
}

TEST(ContourExtraction, ExtractsTheDinoAndWritesTheOverlay) {
  ComponentHarness views(built_plugins(), "vision.image_set", {{"file", kDinoPar}, {"limit", 2}});
  views.run();
  ComponentHarness h(built_plugins(), "vision.contour_extraction");
  for (const auto& p : views.packets("frame")) h.push_packet("frame", p);
  EXPECT_EQ(h.run(), 2);
  const auto& out = h.packets("silhouette");
  ASSERT_EQ(out.size(), 2u);
  const auto& s = out[0].get<fba::Silhouette>();
  const double area = cv::countNonZero(s.mask);
  EXPECT_GT(area, 0.1 * 640 * 480);
  EXPECT_LT(area, 0.6 * 640 * 480);
  EXPECT_EQ(s.contour.size(), s.curvature.size());
  EXPECT_EQ(s.frame->index, 1);
  // A silhouette carries its frame's capture stamp, not the time it was extracted.
  EXPECT_EQ(out[1].header().stamp_ns, views.packets("frame")[1].header().stamp_ns);
}

TEST(ContourExtraction, MetricCurvatureOnlyWhenTheDepthIsGiven) {
  ComponentHarness views(built_plugins(), "vision.image_set", {{"file", kDinoPar}, {"limit", 1}});
  views.run();
  const auto frame = views.packets("frame").at(0);
  ComponentHarness plain(built_plugins(), "vision.contour_extraction");
  plain.push_packet("frame", frame);
  plain.run();
  const auto& a = plain.packets("silhouette").at(0).get<fba::Silhouette>();
  EXPECT_TRUE(a.metric_curvature.empty());
  ComponentHarness metric(built_plugins(), "vision.contour_extraction", {{"depth_m", 0.6}, {"curvature_scale_px", 10.0}});
  metric.push_packet("frame", frame);
  metric.run();
  const auto& b = metric.packets("silhouette").at(0).get<fba::Silhouette>();
  ASSERT_EQ(b.metric_curvature.size(), b.contour.size());
  ASSERT_EQ(b.normals.size(), b.contour.size());
  const double f = 0.5 * (b.frame->camera.K(0, 0) + b.frame->camera.K(1, 1));
  for (std::size_t i = 0; i < b.contour.size(); i += 50) EXPECT_NEAR(b.metric_curvature[i], b.curvature[i] * f / 0.6, 1e-9);
}

TEST(ContourExtraction, KeepsTheFramesStampWhateverTheClock) {
  ComponentHarness views(built_plugins(), "vision.image_set", {{"file", kDinoPar}, {"limit", 1}});
  views.set_time(1'000'000);
  views.run();
  ComponentHarness h(built_plugins(), "vision.contour_extraction");
  h.push_packet("frame", views.packets("frame").at(0));
  h.set_time(9'000'000);
  h.run();
  ASSERT_EQ(h.packets("silhouette").size(), 1u);
  EXPECT_EQ(h.packets("silhouette")[0].header().stamp_ns, 1'000'000);
}

TEST(ContourExtraction, AnEmptyImageIsAnEventNotAFailure) {
  ComponentHarness h(built_plugins(), "vision.contour_extraction");
  fba::Frame black;
  black.image = cv::Mat::zeros(480, 640, CV_8UC3);
  h.push<fba::Frame>("frame", black);
  fba::Frame nothing;  // no pixels at all
  h.push<fba::Frame>("frame", nothing);
  EXPECT_EQ(h.run(), 2);
  EXPECT_TRUE(h.packets("silhouette").empty());
  int no_target = 0;
  for (const auto& e : h.events()) no_target += e.name == "no_target";
  EXPECT_EQ(no_target, 2);
  EXPECT_EQ(h.failure(), "");
}

TEST(SimCamera, RendersTheMeshFromEveryViewpoint) {
  ComponentHarness h(built_plugins(), "sim.camera",
                     {{"mesh", fba::test::ycb_mesh("YcbMustardBottle")}, {"views", 4}, {"noise", 2}});
  EXPECT_EQ(h.run(), 4);
  EXPECT_TRUE(h.finished());
  for (const auto& p : h.packets("frame")) {
    const auto& f = p.get<fba::Frame>();
    cv::Mat grey;
    cv::cvtColor(f.image, grey, cv::COLOR_BGR2GRAY);
    const double object = cv::countNonZero(grey > 60);
    EXPECT_GT(object, 2000) << "view " << f.index;  // the object is in the picture
    EXPECT_LT(object, 0.5 * 640 * 480);
    EXPECT_TRUE(f.has_pose);
  }
}

TEST(SimCamera, RendersFromAPoseItIsGiven) {
  ComponentHarness h(built_plugins(), "sim.camera", {{"mesh", fba::test::kCan}}, {"pose"});
  fba::Pose far;  // looking along +z from far below the object: nothing in view
  far.world_from_frame.translation() << 0, 0, -50;
  h.push<fba::Pose>("pose", far);
  EXPECT_EQ(h.run(), 1);
  const auto& f = h.packets("frame")[0].get<fba::Frame>();
  EXPECT_NEAR(f.camera.centre_in_world().z(), -50, 1e-9);
}

// A read cut short by a stop is not the end of the source: no 'lost', no finish.
TEST(Camera, AnInterruptedCameraStopsReadingWithoutReportingTheSourceLost) {
  const fs::path dir = fs::path(testing::TempDir()) / "camera_interrupt_test";
  fs::create_directories(dir);
  const std::string video = (dir / "two.avi").string();
  {
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 5, cv::Size(64, 48));
    ASSERT_TRUE(writer.isOpened());
    for (int i = 0; i < 2; ++i) writer.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(40 * i)));
  }
  ComponentHarness h(built_plugins(), "vision.camera", {{"source", video}, {"backend", "ffmpeg"}});
  EXPECT_TRUE(h.step());
  EXPECT_EQ(h.packets("frame").size(), 1u);
  h.interrupt();
  h.step();
  EXPECT_EQ(h.packets("frame").size(), 1u);
  EXPECT_FALSE(has_event(h.events(), "lost"));
  EXPECT_FALSE(h.finished());
}

TEST(Camera, IsBlockingAndImplementsInterrupt) {
  const auto camera = built_plugins().find("vision.camera");
  ASSERT_TRUE(camera);
  EXPECT_TRUE(camera->spec.is_blocking());  // registered: Registry::add refuses a blocking type without interrupt()
}

// What `fba-run --check` runs: the carver's bounds are refused at the value, before anything
// is built.
TEST(OctreeCarver, BoundsOfTheWrongLengthFailTheCheckAtTheValue) {
  fba::LoadOptions options;
  options.require_inputs = false;
  try {
    fba::load_task_text("components:\n  carve:\n    type: vision.octree_carver\n    params: { bounds: [1, 2, 3] }\n", "carve.yaml",
                        fs::current_path(), built_plugins(), options);
    FAIL() << "accepted";
  } catch (const fba::ConfigError& e) {
    ASSERT_EQ(e.diagnostics().size(), 1u);
    EXPECT_EQ(e.diagnostics()[0].str(),
              "carve.yaml:4:23: error: component 'carve' (vision.octree_carver): parameter 'bounds' must have 0 or 6 numbers; found 3");
  }
}

// A depth the memory budget cannot hold fails the check, with the figure, not when the carver is
// built mid-run; 10 is past what the octree can address (OctreeNode::kMaxBlocks) whatever the
// budget, so the range stops at 9.
TEST(OctreeCarver, ADepthPastTheMemoryBudgetFailsTheCheckWithTheFigure) {
  fba::LoadOptions options;
  options.require_inputs = false;
  const auto check = [&](const std::string& params) {
    try {
      fba::load_task_text("components:\n  carve:\n    type: vision.octree_carver\n    params: " + params + "\n", "carve.yaml",
                          fs::current_path(), built_plugins(), options);
      return std::string("accepted");
    } catch (const fba::ConfigError& e) {
      return e.diagnostics().at(0).str();
    }
  };
  EXPECT_EQ(check("{ max_depth: 9, memory_budget_mib: 1000 }"),
            "carve.yaml:4:26: error: component 'carve' (vision.octree_carver): max_depth 9 may need up to 2340 MiB, more than "
            "memory_budget_mib (1000); raise it or lower max_depth");
  EXPECT_EQ(check("{ max_depth: 9 }"), "accepted");
  EXPECT_EQ(check("{ max_depth: 10, memory_budget_mib: 20000 }"), "carve.yaml:4:26: error: parameter 'max_depth' must be in [1, 9]; found 10");
}

TEST(OctreeCarver, AnInvertedBoxFailsTheCheck) {
  EXPECT_THROW(ComponentHarness(built_plugins(), "vision.octree_carver", {{"bounds", std::vector<double>{0, 0, 0, 1, -1, 1}}}),
               fba::ConfigError);
  ComponentHarness ok(built_plugins(), "vision.octree_carver", {{"bounds", std::vector<double>{0, 0, 0, 1, 1, 1}}});
  EXPECT_FALSE(ok.finished());
}

TEST(SimCamera, ElevationsOutOfOrderFailTheCheck) {
  try {
    ComponentHarness(built_plugins(), "sim.camera",
                     {{"mesh", fba::test::kCan}, {"min_elevation", 60}, {"max_elevation", 30}});
    FAIL() << "accepted";
  } catch (const fba::ConfigError& e) {
    EXPECT_NE(e.diagnostics().at(0).message.find("parameter 'min_elevation' (60) must be <= parameter 'max_elevation' (30)"),
              std::string::npos)
        << e.what();
  }
}

// A task swaps the real camera for its simulated twin by changing the type alone: the two
// must declare the same ports with the same types.
TEST(SimCamera, IsATwinOfTheRealCamera) {
  const auto real = built_plugins().find("vision.camera");
  const auto twin = built_plugins().find("sim.camera");
  ASSERT_TRUE(real && twin);
  auto ports = [](const std::vector<fba::PortSpec>& v) {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& p : v) out.emplace_back(p.name, p.type->name);
    return out;
  };
  EXPECT_EQ(ports(real->spec.inputs()), ports(twin->spec.inputs()));
  EXPECT_EQ(ports(real->spec.outputs()), ports(twin->spec.outputs()));
  EXPECT_EQ(real->spec.kind(), twin->spec.kind());
}

namespace {

// A unit cube mesh (ASCII PLY) and an octree whose root box is that cube: its root a leaf in
// `state`, at max_depth 3 (8^3 voxels).
std::string unit_cube_ply(const fba::test::TempDir& dir) {
  return dir.file("cube.ply",
                  "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n"
                  "element face 6\nproperty list uchar int vertex_indices\nend_header\n"
                  "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n"
                  "4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n");
}

fba::Octree root_only(fba::NodeState state, int max_depth) {
  fba::Octree t;
  t.bounds = Eigen::AlignedBox3d(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1));
  t.max_depth = max_depth;
  t.views = 4;
  t.root.set_state(state);
  return t;
}

std::string accuracy_payload(ComponentHarness& h) {
  for (const auto& e : h.events())
    if (e.name == "accuracy") return e.payload;
  return {};
}

}  // namespace

// The last model is scored once the stream ends, against the mesh's true voxelisation.
TEST(ModelAccuracy, ScoresTheLastModelAgainstTheMeshsVoxelisation) {
  const fba::test::TempDir dir;
  ComponentHarness h(built_plugins(), "vision.model_accuracy", {{"mesh", unit_cube_ply(dir)}, {"table_clip", false}});
  h.push("octree", root_only(fba::NodeState::Empty, 3));
  h.push("octree", root_only(fba::NodeState::Full, 3));
  h.close("octree");
  h.run();
  ASSERT_TRUE(h.failure().empty()) << h.failure();
  EXPECT_EQ(accuracy_payload(h),
            "{\"voxel_iou\": 1.000000, \"truth_voxels\": 512, \"model_voxels\": 512, \"carved_away\": 0, \"depth\": 3, "
            "\"views\": 4, \"mesh_inside_box\": true}");
}

TEST(ModelAccuracy, AnEmptyModelHasCarvedEverythingAway) {
  const fba::test::TempDir dir;
  ComponentHarness h(built_plugins(), "vision.model_accuracy", {{"mesh", unit_cube_ply(dir)}, {"table_clip", false}});
  h.push("octree", root_only(fba::NodeState::Empty, 3));
  h.close("octree");
  h.run();
  EXPECT_NE(accuracy_payload(h).find("\"voxel_iou\": 0.000000, \"truth_voxels\": 512, \"model_voxels\": 0, \"carved_away\": 512"),
            std::string::npos) << accuracy_payload(h);
}

TEST(ModelAccuracy, AModelDeeperThanItsLimitIsRefusedWithTheMemoryItWouldTake) {
  const fba::test::TempDir dir;
  ComponentHarness h(built_plugins(), "vision.model_accuracy", {{"mesh", unit_cube_ply(dir)}, {"max_depth", 2}});
  h.push("octree", root_only(fba::NodeState::Full, 3));
  h.close("octree");
  h.run();
  EXPECT_NE(h.failure().find("the model's depth 3 is above max_depth 2: its dense grid would take 1024 bytes"), std::string::npos)
      << h.failure();
  EXPECT_TRUE(accuracy_payload(h).empty());
}
