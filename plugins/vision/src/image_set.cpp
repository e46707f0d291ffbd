#include "fba/vision/image_set.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <opencv2/core/persistence.hpp>
#include <opencv2/imgcodecs.hpp>

namespace fba::vision {

namespace fs = std::filesystem;

namespace {

std::string where(const std::string& file, int line) {
  return line > 0 ? file + ":" + std::to_string(line) : file;
}

std::vector<std::string> split_ws(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string tok; in >> tok;) out.push_back(tok);
  return out;
}

bool blank(const std::string& line) {
  return line.find_first_not_of(" \t\r\n") == std::string::npos;
}

double parse_double(const std::string& tok, const std::string& file, int line, const std::string& what) {
  double v = 0;
  const char* end = tok.data() + tok.size();
  auto [p, ec] = std::from_chars(tok.data(), end, v);
  if (ec != std::errc() || p != end || !std::isfinite(v))
    throw FormatError(file, line, "expected a number for " + what + ", found '" + tok + "'");
  return v;
}

// A rotation must be orthonormal with determinant +1; a typo in a calibration file usually
// shows up here first.
void check_rotation(const Eigen::Matrix3d& R, const std::string& file, int line, const std::string& what) {
  const double err = (R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (err > 1e-3 || R.determinant() < 0) {
    std::ostringstream msg;
    msg << "expected " << what << " to be a rotation matrix (orthonormal, det +1), found one with "
        << "|R R^T - I| = " << err << " and det " << R.determinant();
    throw FormatError(file, line, msg.str());
  }
}

std::string resolve(const std::string& base_file, const std::string& name) {
  fs::path p(name);
  if (p.is_absolute()) return p.lexically_normal().string();
  return (fs::path(base_file).parent_path() / p).lexically_normal().string();
}

// Numbers from a YAML node that is either a flow/block sequence or an !!opencv-matrix.
std::vector<double> read_numbers(const cv::FileNode& node, const std::string& file, const std::string& what,
                                 std::size_t expected) {
  if (node.empty() || node.isNone())
    throw FormatError(file, 0, "expected '" + what + "' (" + std::to_string(expected) + " numbers), found nothing");
  std::vector<double> v;
  if (node.isSeq()) {
    for (const auto& n : node) {
      if (!n.isReal() && !n.isInt())
        throw FormatError(file, 0, "expected numbers in '" + what + "', found a non-number element");
      v.push_back(static_cast<double>(n));
    }
  } else if (node.isMap()) {
    cv::Mat m;
    try {
      node >> m;
    } catch (const cv::Exception& e) {
      throw FormatError(file, 0, "expected '" + what + "' as a sequence or an opencv-matrix, found a map that is neither");
    }
    if (m.empty()) throw FormatError(file, 0, "expected '" + what + "' as a sequence or an opencv-matrix, found an empty map");
    m.convertTo(m, CV_64F);
    m = m.reshape(1, 1);
    v.assign(m.begin<double>(), m.end<double>());
  } else {
    throw FormatError(file, 0, "expected '" + what + "' as a sequence of numbers, found a scalar");
  }
  if (expected != 0 && v.size() != expected)
    throw FormatError(file, 0, "expected " + std::to_string(expected) + " numbers in '" + what + "', found " +
                                   std::to_string(v.size()));
  for (double x : v)
    if (!std::isfinite(x)) throw FormatError(file, 0, "expected finite numbers in '" + what + "', found a non-finite one");
  return v;
}

Eigen::Matrix3d matrix3(const std::vector<double>& v) {
  Eigen::Matrix3d m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = v[static_cast<std::size_t>(3 * r + c)];
  return m;
}

void check_intrinsics(const Eigen::Matrix3d& K, const std::string& file, int line) {
  if (!(K(0, 0) > 0 && K(1, 1) > 0 && K(2, 2) == 1 && K(1, 0) == 0 && K(2, 0) == 0 && K(2, 1) == 0)) {
    std::ostringstream msg;
    msg << "expected an upper-triangular camera matrix K with positive focal lengths and K33 = 1, found ["
        << K.row(0) << "; " << K.row(1) << "; " << K.row(2) << "]";
    throw FormatError(file, line, msg.str());
  }
}

cv::Mat distortion_mat(const std::vector<double>& d) {
  if (d.empty()) return {};
  return cv::Mat(d, true).reshape(1, 1);
}


// What a path names, for a message: "a directory", "a character device", ...
std::string kind_of(const fs::file_status& st) {
  switch (st.type()) {
    case fs::file_type::not_found: return "nothing (no such file)";
    case fs::file_type::directory: return "a directory";
    case fs::file_type::character: return "a character device";
    case fs::file_type::block: return "a block device";
    case fs::file_type::fifo: return "a FIFO";
    case fs::file_type::socket: return "a socket";
    default: return "something that is not a regular file";
  }
}

// The set file must be a regular, non-empty text file: OpenCV's YAML reader asserts (or reads
// forever) on anything else, so a folder, a device or an image is named here instead.
void check_set_file(const std::string& file, const std::string& expected) {
  std::error_code ec;
  const fs::file_status st = fs::status(file, ec);
  if (st.type() != fs::file_type::regular) throw FormatError(file, 0, "expected " + expected + ", found " + kind_of(st));
  std::ifstream in(file, std::ios::binary);
  if (!in) throw FormatError(file, 0, "expected " + expected + ", found a file that cannot be read (permissions?)");
  std::array<unsigned char, 4096> head{};
  in.read(reinterpret_cast<char*>(head.data()), head.size());
  const auto n = static_cast<std::size_t>(in.gcount());
  if (n == 0) throw FormatError(file, 0, "expected " + expected + ", found an empty file");
  const auto starts = [&](std::initializer_list<unsigned char> sig) {
    return n >= sig.size() && std::equal(sig.begin(), sig.end(), head.begin());
  };
  const char* image = starts({0x89, 'P', 'N', 'G'})                           ? "a PNG image"
                      : starts({0xFF, 0xD8, 0xFF})                            ? "a JPEG image"
                      : starts({'B', 'M'}) && n > 14                          ? "a BMP image"
                      : starts({'I', 'I', 42, 0}) || starts({'M', 'M', 0, 42}) ? "a TIFF image"
                                                                              : nullptr;
  if (image) throw FormatError(file, 0, "expected " + expected + ", found " + image + " (give the set file that names the images)");
  if (std::find(head.begin(), head.begin() + static_cast<std::ptrdiff_t>(n), 0) != head.begin() + static_cast<std::ptrdiff_t>(n))
    throw FormatError(file, 0, "expected " + expected + ", found binary data (a NUL byte in the first " + std::to_string(n) + " bytes)");
}

std::string num(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

// Each view is checked against the set, so that one wrong line cannot change the model silently:
// a focal length no lens has (the field of view must lie between about 0.1 and 179.9 degrees),
// a camera centre that is not finite or lies orders of magnitude away from the others, and
// (when the views share one camera) an image of another size. lines[i]: view i's line, or 0.
void check_views(const std::vector<ViewDescriptor>& views, const std::string& file, const std::vector<int>& lines,
                 const std::vector<bool>& shared_camera) {
  const auto name = [&](std::size_t i) { return "view '" + views[i].name + "'"; };
  for (std::size_t i = 0; i < views.size(); ++i) {
    const CameraModel& c = views[i].camera;
    const double side = std::max(c.width, c.height);
    const double lo = 1e-3 * side, hi = 1e3 * side;
    const double fx = c.K(0, 0), fy = c.K(1, 1);
    if (!(fx >= lo && fx <= hi && fy >= lo && fy <= hi))
      throw FormatError(file, lines[i],
                        "expected the focal lengths of " + name(i) + " between 0.001 and 1000 times its image's larger side (" +
                            num(lo) + " to " + num(hi) + " px), found fx " + num(fx) + " and fy " + num(fy));
    if (!c.centre_in_world().allFinite() || !std::isfinite(c.centre_in_world().norm()))
      throw FormatError(file, lines[i], "expected a finite camera centre for " + name(i) + ", found one that overflows (translation " +
                                            num(c.camera_from_world.translation().x()) + " " + num(c.camera_from_world.translation().y()) +
                                            " " + num(c.camera_from_world.translation().z()) + ")");
  }
  // The rig's spread: the median distance of the centres from their coordinate-wise median.
  if (views.size() >= 3) {
    Eigen::Vector3d median;
    for (int a = 0; a < 3; ++a) {
      std::vector<double> v;
      for (const auto& d : views) v.push_back(d.camera.centre_in_world()[a]);
      std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
      median[a] = v[v.size() / 2];
    }
    std::vector<double> dist;
    for (const auto& d : views) dist.push_back((d.camera.centre_in_world() - median).norm());
    std::vector<double> sorted = dist;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
    const double spread = sorted[sorted.size() / 2];
    for (std::size_t i = 0; i < views.size(); ++i)
      if (spread > 0 && dist[i] > 1000 * spread)
        throw FormatError(file, lines[i],
                          "expected the camera of " + name(i) + " within 1000 times the set's spread (" + num(spread) +
                              ") of the other cameras, found it " + num(dist[i]) + " away (a translation in other units?)");
  }
  // Views that share one camera have one image size: the most common one.
  std::vector<std::pair<int, int>> sizes;
  for (std::size_t i = 0; i < views.size(); ++i)
    if (shared_camera[i]) sizes.emplace_back(views[i].camera.width, views[i].camera.height);
  std::pair<int, int> common{0, 0};
  std::ptrdiff_t most = 0;
  for (const auto& sz : sizes)
    if (const auto k = std::count(sizes.begin(), sizes.end(), sz); k > most) most = k, common = sz;
  for (std::size_t i = 0; i < views.size(); ++i)
    if (shared_camera[i] && std::make_pair(views[i].camera.width, views[i].camera.height) != common)
      throw FormatError(file, lines[i],
                        "expected " + name(i) + " to be " + std::to_string(common.first) + "x" + std::to_string(common.second) +
                            " like the set's other views (one camera), found " + std::to_string(views[i].camera.width) + "x" +
                            std::to_string(views[i].camera.height) + " (" + views[i].path + ")");
}

// Opens `file` in `storage` for reading; a FormatError when it is not a readable `what`, or not
// well-formed `format` (OpenCV's parser names the line in its message, which is kept).
void open_to_read(cv::FileStorage& storage, const std::string& file, const std::string& what, const std::string& format) {
  try {
    if (!storage.open(file, cv::FileStorage::READ | cv::FileStorage::FORMAT_AUTO))
      throw FormatError(file, 0, "expected a readable " + what + ", found none");
  } catch (const cv::Exception& e) {
    throw FormatError(file, 0, "expected well-formed " + format + ", found a parse error: " + e.msg);
  }
}

}  // namespace

FormatError::FormatError(std::string file, int line, const std::string& what)
    : std::runtime_error(where(file, line) + ": " + what), file_(std::move(file)), line_(line) {}

cv::Size image_file_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FormatError(path, 0, "expected a readable image file, found none (missing or no permission)");
  std::array<unsigned char, 24> h{};
  in.read(reinterpret_cast<char*>(h.data()), h.size());
  static constexpr std::array<unsigned char, 8> png_sig{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (in.gcount() == 24 && std::equal(png_sig.begin(), png_sig.end(), h.begin()) && h[12] == 'I' && h[13] == 'H' &&
      h[14] == 'D' && h[15] == 'R') {
    auto be32 = [&](int o) {
      return static_cast<int>((std::uint32_t(h[o]) << 24) | (std::uint32_t(h[o + 1]) << 16) |
                              (std::uint32_t(h[o + 2]) << 8) | std::uint32_t(h[o + 3]));
    };
    const cv::Size s(be32(16), be32(20));
    if (s.width > 0 && s.height > 0) return s;
  }
  const cv::Mat img = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (img.empty()) throw FormatError(path, 0, "expected an image OpenCV can decode, found undecodable data");
  return img.size();
}

ImageSet ImageSet::load_middlebury(const std::string& par_file, const std::string& good_list) {
  check_set_file(par_file, "a Middlebury parameter file (text: a count line, then one line per image)");
  std::ifstream in(par_file);
  if (!in) throw FormatError(par_file, 0, "expected a readable Middlebury parameter file, found none");
  std::string line;
  int line_no = 0;
  // The count line.
  long count = -1;
  while (std::getline(in, line)) {
    ++line_no;
    if (blank(line)) continue;
    const auto toks = split_ws(line);
    const char* end = toks[0].data() + toks[0].size();
    auto [p, ec] = std::from_chars(toks[0].data(), end, count);
    if (toks.size() != 1 || ec != std::errc() || p != end || count < 0)
      throw FormatError(par_file, line_no, "expected the number of images alone on the first line, found '" + line + "'");
    break;
  }
  if (count < 0) throw FormatError(par_file, line_no, "expected the number of images on the first line, found an empty file");

  std::vector<ViewDescriptor> views;
  std::vector<int> lines;  // each view's line in par_file
  while (std::getline(in, line)) {
    ++line_no;
    if (blank(line)) continue;
    const auto toks = split_ws(line);
    if (toks.size() != 22)
      throw FormatError(par_file, line_no,
                        "expected 22 fields 'name k11..k33 r11..r33 t1 t2 t3', found " + std::to_string(toks.size()));
    std::vector<double> v(21);
    static const char* names[] = {"k11", "k12", "k13", "k21", "k22", "k23", "k31", "k32", "k33", "r11", "r12",
                                  "r13", "r21", "r22", "r23", "r31", "r32", "r33", "t1",  "t2",  "t3"};
    for (int i = 0; i < 21; ++i) v[static_cast<std::size_t>(i)] = parse_double(toks[static_cast<std::size_t>(i + 1)], par_file, line_no, names[i]);
    ViewDescriptor d;
    d.name = toks[0];
    d.path = resolve(par_file, d.name);
    d.index = static_cast<int>(views.size()) + 1;
    d.camera.K = matrix3({v.begin(), v.begin() + 9});
    check_intrinsics(d.camera.K, par_file, line_no);
    const Eigen::Matrix3d R = matrix3({v.begin() + 9, v.begin() + 18});
    check_rotation(R, par_file, line_no, "r11..r33");
    d.camera.camera_from_world.linear() = R;
    d.camera.camera_from_world.translation() = Eigen::Vector3d(v[18], v[19], v[20]);
    views.push_back(std::move(d));
    lines.push_back(line_no);
  }
  if (static_cast<long>(views.size()) != count)
    throw FormatError(par_file, 1, "expected " + std::to_string(count) + " image lines as the count line says, found " +
                                       std::to_string(views.size()));

  if (!good_list.empty()) {
    std::ifstream gin(good_list);
    if (!gin) throw FormatError(good_list, 0, "expected a readable list of good images, found none");
    std::vector<ViewDescriptor> kept;
    std::vector<int> kept_lines;
    int gline = 0;
    while (std::getline(gin, line)) {
      ++gline;
      if (blank(line)) continue;
      const auto toks = split_ws(line);
      if (toks.size() != 1)
        throw FormatError(good_list, gline, "expected one image name per line, found '" + line + "'");
      auto it = std::find_if(views.begin(), views.end(), [&](const ViewDescriptor& d) { return d.name == toks[0]; });
      if (it == views.end())
        throw FormatError(good_list, gline, "expected an image named in " + par_file + ", found '" + toks[0] + "'");
      kept.push_back(*it);
      kept_lines.push_back(lines[static_cast<std::size_t>(it - views.begin())]);
    }
    views = std::move(kept);
    lines = std::move(kept_lines);
  }
  for (auto& d : views) {
    const cv::Size s = image_file_size(d.path);
    d.camera.width = s.width;
    d.camera.height = s.height;
  }
  check_views(views, par_file, lines, std::vector<bool>(views.size(), true));  // one camera took them all
  return ImageSet(std::move(views));
}

ImageSet ImageSet::load_yaml(const std::string& file) {
  check_set_file(file, "an fba image-set YAML file (docs/image-set-format.md) or a Middlebury *_par.txt");
  try {
    return load_yaml_checked(file);
  } catch (const cv::Exception& e) {  // a node of an unexpected kind read as a number or string
    throw FormatError(file, 0, "expected an fba image-set YAML file (docs/image-set-format.md), found content OpenCV refuses: " + e.msg);
  }
}

ImageSet ImageSet::load_yaml_checked(const std::string& file) {
  cv::FileStorage fsr;
  open_to_read(fsr, file, "an fba image-set YAML file", "YAML");
  const cv::FileNode root = fsr.root();
  const cv::FileNode images = root["images"];
  if (images.empty() || !images.isSeq())
    throw FormatError(file, 0, "expected a sequence 'images', found " + std::string(images.empty() ? "none" : "another node type"));
  std::vector<double> default_K, default_dist;
  if (!root["K"].empty()) default_K = read_numbers(root["K"], file, "K", 9);
  if (!root["distortion"].empty()) default_dist = read_numbers(root["distortion"], file, "distortion", 0);

  std::vector<ViewDescriptor> views;
  std::vector<bool> shared_camera;  // the view takes the top-level K
  int i = 0;
  for (const auto& img : images) {
    const std::string ctx = "images[" + std::to_string(i) + "]";
    if (!img.isMap()) throw FormatError(file, 0, "expected " + ctx + " to be a map, found another node type");
    ViewDescriptor d;
    d.index = i + 1;
    if (!img["path"].isString()) throw FormatError(file, 0, "expected a string " + ctx + ".path, found none");
    d.name = static_cast<std::string>(img["path"]);
    d.path = resolve(file, d.name);
    std::vector<double> K = img["K"].empty() ? default_K : read_numbers(img["K"], file, ctx + ".K", 9);
    if (K.empty()) throw FormatError(file, 0, "expected K in " + ctx + " or at the top level, found none");
    shared_camera.push_back(img["K"].empty());
    d.camera.K = matrix3(K);
    check_intrinsics(d.camera.K, file, 0);
    d.camera.distortion = distortion_mat(img["distortion"].empty() ? default_dist
                                                                    : read_numbers(img["distortion"], file, ctx + ".distortion", 0));
    if (!d.camera.distortion.empty() && d.camera.distortion.total() != 4 && d.camera.distortion.total() != 5 &&
        d.camera.distortion.total() != 8 && d.camera.distortion.total() != 12 && d.camera.distortion.total() != 14)
      throw FormatError(file, 0, "expected 4, 5, 8, 12 or 14 distortion coefficients in " + ctx + ", found " +
                                     std::to_string(d.camera.distortion.total()));
    const bool has_rt = !img["R"].empty() || !img["t"].empty();
    const bool has_pose = !img["world_from_camera"].empty();
    if (has_rt == has_pose)
      throw FormatError(file, 0, "expected either R and t or world_from_camera in " + ctx + ", found " +
                                     (has_rt ? "both" : "neither"));
    if (has_rt) {
      const Eigen::Matrix3d R = matrix3(read_numbers(img["R"], file, ctx + ".R", 9));
      check_rotation(R, file, 0, ctx + ".R");
      const auto t = read_numbers(img["t"], file, ctx + ".t", 3);
      d.camera.camera_from_world.linear() = R;
      d.camera.camera_from_world.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
    } else {
      const auto m = read_numbers(img["world_from_camera"], file, ctx + ".world_from_camera", 16);
      Eigen::Matrix4d T;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) T(r, c) = m[static_cast<std::size_t>(4 * r + c)];
      if (T.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
        throw FormatError(file, 0, "expected the last row of " + ctx + ".world_from_camera to be 0 0 0 1");
      check_rotation(T.topLeftCorner<3, 3>(), file, 0, ctx + ".world_from_camera rotation");
      Eigen::Isometry3d w;
      w.matrix() = T;
      d.camera.camera_from_world = w.inverse();
    }
    if (!img["mask"].empty()) {
      if (!img["mask"].isString()) throw FormatError(file, 0, "expected " + ctx + ".mask to be a path, found another node type");
      d.mask_path = resolve(file, static_cast<std::string>(img["mask"]));
    }
    if (!img["width"].empty() && !img["height"].empty()) {
      d.camera.width = static_cast<int>(img["width"]);
      d.camera.height = static_cast<int>(img["height"]);
      if (d.camera.width <= 0 || d.camera.height <= 0)
        throw FormatError(file, 0, "expected positive width and height in " + ctx);
    } else {
      const cv::Size s = image_file_size(d.path);
      d.camera.width = s.width;
      d.camera.height = s.height;
    }
    views.push_back(std::move(d));
    ++i;
  }
  check_views(views, file, std::vector<int>(views.size(), 0), shared_camera);
  return ImageSet(std::move(views));
}

ImageSet ImageSet::load(const std::string& file, bool use_good_list) {
  const fs::path p(file);
  const std::string name = p.filename().string();
  const std::string suffix = "_par.txt";
  if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
    const std::string stem = name.substr(0, name.size() - suffix.size());
    const fs::path good = p.parent_path() / (stem + "_good_silhouette_images.txt");
    return load_middlebury(file, use_good_list && fs::exists(good) ? good.string() : std::string());
  }
  return load_yaml(file);
}

void ImageSet::save_yaml(const std::string& file) const {
  cv::FileStorage out(file, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  if (!out.isOpened()) throw FormatError(file, 0, "expected a writable file, found none");
  const fs::path dir = fs::absolute(fs::path(file)).parent_path();
  out << "images" << "[";
  for (const auto& d : views_) {
    out << "{";
    out << "path" << fs::relative(fs::absolute(d.path), dir).generic_string();
    if (!d.mask_path.empty()) out << "mask" << fs::relative(fs::absolute(d.mask_path), dir).generic_string();
    out << "width" << d.camera.width << "height" << d.camera.height;
    out << "K" << "[:";
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out << d.camera.K(r, c);
    out << "]";
    out << "distortion" << "[:";
    if (!d.camera.distortion.empty()) {
      cv::Mat dist;
      d.camera.distortion.convertTo(dist, CV_64F);
      for (auto it = dist.begin<double>(); it != dist.end<double>(); ++it) out << *it;
    }
    out << "]";
    out << "R" << "[:";
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out << d.camera.camera_from_world.linear()(r, c);
    out << "]";
    out << "t" << "[:";
    for (int r = 0; r < 3; ++r) out << d.camera.camera_from_world.translation()(r);
    out << "]";
    out << "}";
  }
  out << "]";
}

Frame ImageSet::load_frame(std::size_t i) const {
  const ViewDescriptor& d = views_.at(i);
  Frame f;
  f.image = cv::imread(d.path, cv::IMREAD_ANYCOLOR);
  if (f.image.empty()) throw FormatError(d.path, 0, "expected an image OpenCV can decode, found a missing or undecodable file");
  if (f.image.cols != d.camera.width || f.image.rows != d.camera.height)
    throw FormatError(d.path, 0,
                      "expected a " + std::to_string(d.camera.width) + "x" + std::to_string(d.camera.height) +
                          " image as when the set was loaded, found " + std::to_string(f.image.cols) + "x" +
                          std::to_string(f.image.rows));
  f.camera = d.camera;
  f.has_pose = true;
  f.source = d.path;
  f.index = d.index;
  return f;
}

bool ImageSet::has_masks() const {
  return !views_.empty() && std::all_of(views_.begin(), views_.end(), [](const ViewDescriptor& d) { return !d.mask_path.empty(); });
}

cv::Mat ImageSet::load_mask(std::size_t i) const {
  const ViewDescriptor& d = views_.at(i);
  if (d.mask_path.empty()) throw FormatError(d.path, 0, "expected a mask for view '" + d.name + "', found none in the set");
  const cv::Mat m = cv::imread(d.mask_path, cv::IMREAD_GRAYSCALE);
  if (m.empty()) throw FormatError(d.mask_path, 0, "expected a mask image OpenCV can decode, found a missing or undecodable file");
  if (m.cols != d.camera.width || m.rows != d.camera.height)
    throw FormatError(d.mask_path, 0,
                      "expected a " + std::to_string(d.camera.width) + "x" + std::to_string(d.camera.height) + " mask like view '" +
                          d.name + "', found " + std::to_string(m.cols) + "x" + std::to_string(m.rows));
  return m != 0;
}

std::optional<std::size_t> ImageSet::nearest_unserved_view(const Eigen::Isometry3d& requested,
                                                           const std::set<std::size_t>& served,
                                                           double angle_weight) const {
  std::optional<std::size_t> best;
  double best_cost = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d axis = requested.linear().col(2);  // the optical axis (camera z) in world
  for (std::size_t i = 0; i < views_.size(); ++i) {
    if (served.count(i)) continue;
    const Eigen::Isometry3d w = views_[i].camera.camera_from_world.inverse();
    const double d = (w.translation() - requested.translation()).norm();
    const double a = std::acos(std::clamp(w.linear().col(2).dot(axis), -1.0, 1.0));
    const double cost = d + angle_weight * a;
    if (cost < best_cost) best_cost = cost, best = i;
  }
  return best;
}

std::optional<std::size_t> ImageSet::nearest_unserved_view(const Eigen::Vector3d& centre,
                                                           const std::set<std::size_t>& served) const {
  std::optional<std::size_t> best;
  double best_d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < views_.size(); ++i) {
    if (served.count(i)) continue;
    const double d = (views_[i].camera.centre_in_world() - centre).norm();
    if (d < best_d) best_d = d, best = i;
  }
  return best;
}

CameraModel load_opencv_calibration(const std::string& file) {
  cv::FileStorage in;
  open_to_read(in, file, "an OpenCV calibration file", "YAML/XML");
  CameraModel cam;
  const auto K = read_numbers(in["camera_matrix"], file, "camera_matrix", 9);
  cam.K = matrix3(K);
  check_intrinsics(cam.K, file, 0);
  cam.distortion = distortion_mat(read_numbers(in["distortion_coefficients"], file, "distortion_coefficients", 0));
  const cv::FileNode w = in["image_width"], h = in["image_height"];
  if (!w.isInt() || !h.isInt())
    throw FormatError(file, 0, "expected integers image_width and image_height, found " +
                                   std::string(w.empty() || h.empty() ? "none" : "non-integers"));
  cam.width = static_cast<int>(w);
  cam.height = static_cast<int>(h);
  if (cam.width <= 0 || cam.height <= 0)
    throw FormatError(file, 0, "expected positive image_width and image_height, found " + std::to_string(cam.width) +
                                   "x" + std::to_string(cam.height));
  return cam;
}

}  // namespace fba::vision
