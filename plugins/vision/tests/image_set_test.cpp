#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

#include "fba/vision/image_set.hpp"
#include "support/temp_dir.hpp"
#include "support/build_paths.hpp"
#include "support/data_sets.hpp"

namespace fs = std::filesystem;
using namespace fba::vision;

namespace {

using fba::test::kDino;

using fba::test::TempDir;

// Runs f, which must throw FormatError; returns its message.
template <class F>
std::string format_error(F f) {
  try {
    f();
  } catch (const FormatError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no FormatError thrown";
  return {};
}

const char* kGoodLine =
    "a.png 100 0 50 0 100 40 0 0 1 1 0 0 0 1 0 0 0 1 0.1 0.2 0.3\n";

}  // namespace

TEST(MiddleburyParsing, ReadsCountAndViewOneAsInTheFile) {
  const ImageSet set = ImageSet::load_middlebury(kDino + "/dinoSR_par.txt");
  ASSERT_EQ(set.size(), 16u);
  const auto& v = set[0];
  EXPECT_EQ(v.name, "dinoSR0001.png");
  EXPECT_EQ(v.index, 1);
  EXPECT_TRUE(fs::exists(v.path));
  EXPECT_EQ(v.camera.width, 640);
  EXPECT_EQ(v.camera.height, 480);
  // First line of dinoSR_par.txt.
  EXPECT_DOUBLE_EQ(v.camera.K(0, 0), 3310.4);
  EXPECT_DOUBLE_EQ(v.camera.K(0, 2), 316.73);
  EXPECT_DOUBLE_EQ(v.camera.K(1, 1), 3325.5);
  EXPECT_DOUBLE_EQ(v.camera.K(1, 2), 200.55);
  const Eigen::Matrix3d R = v.camera.camera_from_world.linear();
  EXPECT_DOUBLE_EQ(R(0, 0), -0.14396457836077139000);
  EXPECT_DOUBLE_EQ(R(0, 1), 0.96965263281337499000);
  EXPECT_DOUBLE_EQ(R(1, 0), -0.90366580603479685000);
  EXPECT_DOUBLE_EQ(R(2, 2), 0.88306936201487163000);
  const Eigen::Vector3d t = v.camera.camera_from_world.translation();
  EXPECT_DOUBLE_EQ(t.x(), -0.010415508744);
  EXPECT_DOUBLE_EQ(t.y(), -0.0294278883669);
  EXPECT_DOUBLE_EQ(t.z(), 0.673097816109);
}

TEST(MiddleburyParsing, GoodListKeepsFifteenViewsWithoutViewSix) {
  const ImageSet set = ImageSet::load(kDino + "/dinoSR_par.txt");
  ASSERT_EQ(set.size(), 15u);
  for (const auto& v : set.views()) EXPECT_NE(v.name, "dinoSR0006.png");
  EXPECT_EQ(set[5].name, "dinoSR0007.png");
  EXPECT_EQ(set[5].index, 7);  // numbering of the par file, not of the list
}

TEST(MiddleburyParsing, MalformedFilesNameFileLineExpectedAndFound) {
  TempDir dir;
  const std::string few = dir.file("few_par.txt", std::string("1\na.png 100 0 50\n"));
  std::string m = format_error([&] { ImageSet::load_middlebury(few); });
  EXPECT_NE(m.find(few + ":2"), std::string::npos) << m;
  EXPECT_NE(m.find("expected 22 fields"), std::string::npos) << m;
  EXPECT_NE(m.find("found 4"), std::string::npos) << m;

  std::string bad_num_text = std::string("1\n") + kGoodLine;
  bad_num_text.replace(bad_num_text.find(" 0.2 "), 5, " x.y ");
  const std::string bad_num = dir.file("num_par.txt", bad_num_text);
  m = format_error([&] { ImageSet::load_middlebury(bad_num); });
  EXPECT_NE(m.find(bad_num + ":2"), std::string::npos) << m;
  EXPECT_NE(m.find("t2"), std::string::npos) << m;
  EXPECT_NE(m.find("'x.y'"), std::string::npos) << m;

  const std::string count = dir.file("count_par.txt", std::string("3\n") + kGoodLine);
  m = format_error([&] { ImageSet::load_middlebury(count); });
  EXPECT_NE(m.find("expected 3 image lines"), std::string::npos) << m;
  EXPECT_NE(m.find("found 1"), std::string::npos) << m;

  const std::string header = dir.file("header_par.txt", std::string("three\n") + kGoodLine);
  m = format_error([&] { ImageSet::load_middlebury(header); });
  EXPECT_NE(m.find(header + ":1"), std::string::npos) << m;

  std::string rot_text = std::string("1\n") + kGoodLine;
  rot_text.replace(rot_text.find(" 1 0 0 0 1 0 0 0 1 "), 19, " 2 0 0 0 1 0 0 0 1 ");
  const std::string rot = dir.file("rot_par.txt", rot_text);
  m = format_error([&] { ImageSet::load_middlebury(rot); });
  EXPECT_NE(m.find("rotation"), std::string::npos) << m;

  // The image named by a good line does not exist beside the file.
  const std::string missing = dir.file("missing_par.txt", std::string("1\n") + kGoodLine);
  m = format_error([&] { ImageSet::load_middlebury(missing); });
  EXPECT_NE(m.find("a.png"), std::string::npos) << m;

  const std::string list = dir.file("list.txt", "dinoSR0001.png\nnot_there.png\n");
  m = format_error([&] { ImageSet::load_middlebury(kDino + "/dinoSR_par.txt", list); });
  EXPECT_NE(m.find(list + ":2"), std::string::npos) << m;
  EXPECT_NE(m.find("not_there.png"), std::string::npos) << m;

  m = format_error([&] { ImageSet::load_middlebury(dir.file("nope_par.txt")); });
  EXPECT_NE(m.find("nope_par.txt"), std::string::npos) << m;
}

TEST(OwnFormat, RoundTripKeepsCamerasAndImagePaths) {
  TempDir dir;
  const ImageSet dino = ImageSet::load(kDino + "/dinoSR_par.txt");
  const std::string file = dir.file("dino.yaml");
  dino.save_yaml(file);
  const ImageSet back = ImageSet::load_yaml(file);
  ASSERT_EQ(back.size(), dino.size());
  for (std::size_t i = 0; i < dino.size(); ++i) {
    EXPECT_EQ(fs::weakly_canonical(back[i].path), fs::weakly_canonical(dino[i].path));
    EXPECT_EQ(back[i].camera.width, 640);
    EXPECT_TRUE(back[i].camera.K.isApprox(dino[i].camera.K, 1e-12));
    EXPECT_TRUE(back[i].camera.camera_from_world.matrix().isApprox(dino[i].camera.camera_from_world.matrix(), 1e-12));
  }
  const fba::Frame f = back.load_frame(3);
  EXPECT_EQ(f.image.cols, 640);
  EXPECT_TRUE(f.has_pose);
}

TEST(OwnFormat, ReadsSharedIntrinsicsAndWorldFromCamera) {
  TempDir dir;
  cv::imwrite(dir.file("img.png"), cv::Mat(30, 40, CV_8UC1, cv::Scalar(7)));
  const std::string file = dir.file("set.yaml",
                                    "%YAML:1.0\n---\n"
                                    "K: [500, 0, 20, 0, 500, 15, 0, 0, 1]\n"
                                    "distortion: [0.1, -0.01, 0, 0, 0]\n"
                                    "images:\n"
                                    "  - path: img.png\n"
                                    "    world_from_camera: [1, 0, 0, 0.5,  0, 1, 0, 0,  0, 0, 1, -1,  0, 0, 0, 1]\n");
  const ImageSet set = ImageSet::load_yaml(file);
  ASSERT_EQ(set.size(), 1u);
  EXPECT_EQ(set[0].camera.width, 40);
  EXPECT_EQ(set[0].camera.height, 30);
  EXPECT_DOUBLE_EQ(set[0].camera.K(0, 0), 500);
  ASSERT_EQ(set[0].camera.distortion.total(), 5u);
  EXPECT_DOUBLE_EQ(set[0].camera.distortion.at<double>(0), 0.1);
  EXPECT_TRUE(set[0].camera.centre_in_world().isApprox(Eigen::Vector3d(0.5, 0, -1)));
}

TEST(OwnFormat, MalformedFilesGiveClearErrors) {
  TempDir dir;
  std::string m = format_error([&] { ImageSet::load_yaml(dir.file("a.yaml", "%YAML:1.0\n---\nviews: []\n")); });
  EXPECT_NE(m.find("expected a sequence 'images'"), std::string::npos) << m;
  m = format_error([&] {
    ImageSet::load_yaml(dir.file("b.yaml", "%YAML:1.0\n---\nimages:\n  - { path: x.png, K: [1,0,0,0,1,0,0,0,1], "
                                           "R: [1,0,0,0,1,0,0,0], t: [0,0,0], width: 4, height: 4 }\n"));
  });
  EXPECT_NE(m.find("images[0].R"), std::string::npos) << m;
  EXPECT_NE(m.find("expected 9 numbers"), std::string::npos) << m;
  EXPECT_NE(m.find("found 8"), std::string::npos) << m;
  m = format_error([&] {
    ImageSet::load_yaml(dir.file("c.yaml", "%YAML:1.0\n---\nimages:\n  - { path: x.png, K: [1,0,0,0,1,0,0,0,1], "
                                           "width: 4, height: 4 }\n"));
  });
  EXPECT_NE(m.find("either R and t or world_from_camera"), std::string::npos) << m;
  m = format_error([&] { ImageSet::load_yaml(dir.file("d.yaml", "%YAML:1.0\n---\nimages: [ {path: \n")); });
  EXPECT_NE(m.find("d.yaml"), std::string::npos) << m;
}

TEST(CalibrationFile, LoadsOpenCvCalibrationYamlAndXml) {
  TempDir dir;
  for (const std::string name : {"calib.yml", "calib.xml"}) {
    const std::string file = dir.file(name);
    {
      // As OpenCV's calibration sample writes it.
      cv::FileStorage out(file, cv::FileStorage::WRITE);
      out << "image_width" << 1280 << "image_height" << 720;
      out << "camera_matrix" << (cv::Mat_<double>(3, 3) << 900, 0, 640.5, 0, 910, 360.25, 0, 0, 1);
      out << "distortion_coefficients" << (cv::Mat_<double>(5, 1) << -0.2, 0.05, 0.001, -0.002, 0.0);
      out << "avg_reprojection_error" << 0.3;
    }
    const fba::CameraModel cam = load_opencv_calibration(file);
    EXPECT_EQ(cam.width, 1280);
    EXPECT_EQ(cam.height, 720);
    EXPECT_DOUBLE_EQ(cam.K(0, 0), 900);
    EXPECT_DOUBLE_EQ(cam.K(1, 1), 910);
    EXPECT_DOUBLE_EQ(cam.K(0, 2), 640.5);
    EXPECT_DOUBLE_EQ(cam.K(1, 2), 360.25);
    ASSERT_EQ(cam.distortion.total(), 5u);
    EXPECT_DOUBLE_EQ(cam.distortion.at<double>(0), -0.2);
    EXPECT_DOUBLE_EQ(cam.distortion.at<double>(3), -0.002);
  }
}

TEST(CalibrationFile, MissingFieldsGiveClearErrors) {
  TempDir dir;
  const std::string file = dir.file("calib.yml");
  {
    cv::FileStorage out(file, cv::FileStorage::WRITE);
    out << "camera_matrix" << cv::Mat::eye(3, 3, CV_64F);
    out << "distortion_coefficients" << cv::Mat::zeros(5, 1, CV_64F);
  }
  const std::string m = format_error([&] { load_opencv_calibration(file); });
  EXPECT_NE(m.find(file), std::string::npos) << m;
  EXPECT_NE(m.find("image_width"), std::string::npos) << m;
}

TEST(ImageSetFrames, UnreadableImageThrowsNamingTheFile) {
  TempDir dir;
  const std::string png = dir.file("broken.png", "this is not a png");
  fba::CameraModel cam;
  cam.width = 10, cam.height = 10;
  const ImageSet set({ViewDescriptor{"broken.png", png, 1, cam}});
  try {
    set.load_frame(0);
    FAIL() << "no exception";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find(png), std::string::npos) << e.what();
  }
  EXPECT_THROW(image_file_size(png), FormatError);
}

TEST(Exploration, NearestUnservedViewSkipsServedViews) {
  const ImageSet set = ImageSet::load(kDino + "/dinoSR_par.txt");
  const Eigen::Vector3d c3 = set[3].camera.centre_in_world();
  EXPECT_EQ(set.nearest_unserved_view(c3, {}), std::optional<std::size_t>(3));
  const auto next = set.nearest_unserved_view(c3, {3});
  ASSERT_TRUE(next.has_value());
  EXPECT_NE(*next, 3u);
  // It is the nearest of the others.
  for (std::size_t i = 0; i < set.size(); ++i)
    if (i != 3) EXPECT_LE((set[*next].camera.centre_in_world() - c3).norm(), (set[i].camera.centre_in_world() - c3).norm() + 1e-12);
  // By pose: the requested pose of view 5 gives view 5.
  EXPECT_EQ(set.nearest_unserved_view(set[5].camera.camera_from_world.inverse(), {}), std::optional<std::size_t>(5));
  std::set<std::size_t> all;
  for (std::size_t i = 0; i < set.size(); ++i) all.insert(i);
  EXPECT_FALSE(set.nearest_unserved_view(c3, all).has_value());
}

// Each view is checked against the set: one wrong line must not change the model silently.
TEST(ImageSetConsistency, ViewsSharingACameraMustShareItsImageSize) {
  TempDir dir;
  cv::imwrite(dir.file("a.png"), cv::Mat(30, 40, CV_8UC1, cv::Scalar(0)));
  cv::imwrite(dir.file("b.png"), cv::Mat(30, 41, CV_8UC1, cv::Scalar(0)));
  const std::string head = "%YAML:1.0\n---\nK: [50, 0, 20, 0, 50, 15, 0, 0, 1]\nimages:\n";
  const std::string m = format_error([&] {
    ImageSet::load_yaml(dir.file("shared.yaml", head + "  - { path: a.png, R: [1,0,0,0,1,0,0,0,1], t: [0,0,1] }\n"
                                                       "  - { path: b.png, R: [1,0,0,0,1,0,0,0,1], t: [0,0,2] }\n"));
  });
  EXPECT_NE(m.find("expected view 'b.png' to be 40x30 like the set's other views (one camera), found 41x30"), std::string::npos) << m;
  // A view with a camera of its own (its own K) may have another size.
  const ImageSet set = ImageSet::load_yaml(
      dir.file("own.yaml", head + "  - { path: a.png, R: [1,0,0,0,1,0,0,0,1], t: [0,0,1] }\n"
                                  "  - { path: b.png, K: [50, 0, 20, 0, 50, 15, 0, 0, 1], R: [1,0,0,0,1,0,0,0,1], t: [0,0,2] }\n"));
  EXPECT_EQ(set.size(), 2u);
}

TEST(ImageSetConsistency, FocalLengthNoLensHasIsRefusedWithTheLine) {
  TempDir dir;
  cv::imwrite(dir.file("a.png"), cv::Mat(50, 100, CV_8UC1, cv::Scalar(0)));
  const std::string far = "a.png 1e-300 0 50 0 1e-300 40 0 0 1 1 0 0 0 1 0 0 0 1 0.1 0.2 0.3\n";
  const std::string m = format_error([&] { ImageSet::load_middlebury(dir.file("x_par.txt", std::string("2\n") + kGoodLine + far)); });
  EXPECT_NE(m.find("x_par.txt:3: expected the focal lengths of view 'a.png' between 0.001 and 1000 times its image's larger "
                   "side (0.1 to 100000 px), found fx 1e-300"),
            std::string::npos) << m;
}

TEST(ImageSetConsistency, CameraFarFromTheOthersIsRefusedWithTheLine) {
  TempDir dir;
  cv::imwrite(dir.file("a.png"), cv::Mat(50, 100, CV_8UC1, cv::Scalar(0)));
  const std::string set = std::string("4\n") + kGoodLine + "a.png 100 0 50 0 100 40 0 0 1 1 0 0 0 1 0 0 0 1 0.2 0.2 0.3\n" +
                          "a.png 100 0 50 0 100 40 0 0 1 1 0 0 0 1 0 0 0 1 0.1 0.3 0.3\n" +
                          "a.png 100 0 50 0 100 40 0 0 1 1 0 0 0 1 0 0 0 1 0.1 0.2 300\n";  // millimetres
  std::string m = format_error([&] { ImageSet::load_middlebury(dir.file("x_par.txt", set)); });
  EXPECT_NE(m.find("x_par.txt:5: expected the camera of view 'a.png' within 1000 times the set's spread"), std::string::npos) << m;
  const std::string overflow = std::string("2\n") + kGoodLine + "a.png 100 0 50 0 100 40 0 0 1 1 0 0 0 1 0 0 0 1 0 0 1e308\n";
  m = format_error([&] { ImageSet::load_middlebury(dir.file("y_par.txt", overflow)); });
  EXPECT_NE(m.find("y_par.txt:3: expected a finite camera centre for view 'a.png', found one that overflows (translation 0 0 1e+308)"),
            std::string::npos) << m;
}

TEST(ImageSetConsistency, SetFileThatIsAFolderDeviceOrImageIsNamedForWhatItIs) {
  TempDir dir;
  cv::imwrite(dir.file("a.png"), cv::Mat(50, 100, CV_8UC1, cv::Scalar(0)));
  EXPECT_NE(format_error([&] { ImageSet::load(dir.path().string()); }).find("found a directory"), std::string::npos);
  EXPECT_NE(format_error([&] { ImageSet::load("/dev/null"); }).find("found a character device"), std::string::npos);
  EXPECT_NE(format_error([&] { ImageSet::load(dir.file("a.png")); }).find("found a PNG image"), std::string::npos);
  std::ofstream(dir.file("e.yaml")).close();
  EXPECT_NE(format_error([&] { ImageSet::load(dir.file("e.yaml")); }).find("found an empty file"), std::string::npos);
  EXPECT_NE(format_error([&] { ImageSet::load(dir.file("z_par.txt", std::string("1\0x", 3))); }).find("found binary data"),
            std::string::npos);
}

TEST(OwnFormat, MasksAreReadWrittenAndCheckedAgainstTheirView) {
  TempDir dir;
  cv::imwrite(dir.file("img.png"), cv::Mat(30, 40, CV_8UC1, cv::Scalar(7)));
  cv::Mat mask(30, 40, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(10, 5, 20, 10)) = 1;
  cv::imwrite(dir.file("mask.png"), mask);
  cv::imwrite(dir.file("small.png"), cv::Mat(30, 39, CV_8UC1, cv::Scalar(0)));
  const std::string head = "%YAML:1.0\n---\nK: [500, 0, 20, 0, 500, 15, 0, 0, 1]\nimages:\n";
  const ImageSet set = ImageSet::load_yaml(dir.file("set.yaml", head + "  - { path: img.png, mask: mask.png, R: [1,0,0,0,1,0,0,0,1], t: [0,0,1] }\n"));
  ASSERT_TRUE(set.has_masks());
  const cv::Mat m = set.load_mask(0);
  EXPECT_EQ(cv::countNonZero(m), 200);
  EXPECT_EQ(m.at<std::uint8_t>(5, 10), 255);
  set.save_yaml(dir.file("again.yaml"));
  EXPECT_EQ(cv::countNonZero(ImageSet::load_yaml(dir.file("again.yaml")).load_mask(0)), 200);
  const ImageSet wrong = ImageSet::load_yaml(dir.file("wrong.yaml", head + "  - { path: img.png, mask: small.png, R: [1,0,0,0,1,0,0,0,1], t: [0,0,1] }\n"));
  const std::string e = format_error([&] { wrong.load_mask(0); });
  EXPECT_NE(e.find("expected a 40x30 mask like view 'img.png', found 39x30"), std::string::npos) << e;
  const ImageSet none = ImageSet::load_yaml(dir.file("none.yaml", head + "  - { path: img.png, R: [1,0,0,0,1,0,0,0,1], t: [0,0,1] }\n"));
  EXPECT_FALSE(none.has_masks());
}
