// Reading a batch list: every mapping checked for unknown and repeated keys, every value for its
// kind, and random_runs drawn the same way on any machine.
#include "batch_list.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <stdexcept>
#include <utility>

#include <yaml-cpp/yaml.h>

namespace fba::evaluate::batch {

namespace fs = std::filesystem;
namespace {

class ListReader {
 public:
  explicit ListReader(fs::path file) : file_(std::move(file)) {}

  // file:line:column of the node (the file alone for a node the file does not have).
  std::string where(const YAML::Node& at) const {
    std::string w = file_.string();
    if (at.IsDefined() && at.Mark().line >= 0) w += ":" + std::to_string(at.Mark().line + 1) + ":" + std::to_string(at.Mark().column + 1);
    return w;
  }

  [[noreturn]] void fail(const YAML::Node& at, const std::string& what) const { throw std::invalid_argument(where(at) + ": " + what); }

  static std::string found(const YAML::Node& n) {
    if (n.IsScalar()) return "'" + n.Scalar() + "'";
    if (n.IsSequence()) return n.size() == 0 ? "an empty list" : "a list of " + std::to_string(n.size());
    if (n.IsMap()) return n.size() == 0 ? "an empty mapping" : "a mapping";
    return "nothing";
  }

  // yaml-cpp keeps both of two equal keys and answers a lookup with the first: the second would
  // be ignored silently, so every mapping of the list is checked for one.
  void check_no_duplicate_keys(const YAML::Node& n) const {
    if (n.IsSequence())
      for (const auto& item : n) check_no_duplicate_keys(item);
    if (!n.IsMap()) return;
    std::map<std::string, YAML::Node> seen;
    for (const auto& kv : n) {
      if (kv.first.IsScalar()) {
        const auto [first, fresh] = seen.emplace(kv.first.Scalar(), kv.first);
        if (!fresh)
          fail(kv.first, "duplicate key '" + kv.first.Scalar() + "': expected each key once, found it at " + where(first->second) +
                             " already");
      }
      check_no_duplicate_keys(kv.second);
    }
  }

  std::string text(const YAML::Node& n, const std::string& what) const {
    if (!n.IsScalar() || n.Scalar().empty()) fail(n, what + ": expected a text, found " + found(n));
    return n.Scalar();
  }

  double number(const YAML::Node& n, const std::string& what) const {
    if (const auto v = parsed<double>(n); v && std::isfinite(*v)) return *v;
    fail(n, what + ": expected a number, found " + found(n));
  }

  std::uint64_t whole(const YAML::Node& n, const std::string& what, std::uint64_t lo, std::uint64_t hi) const {
    if (const auto v = parsed<std::uint64_t>(n); v && *v >= lo && *v <= hi) return *v;
    fail(n, what + ": expected a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) + ", found " + found(n));
  }

  // [lo, hi] with lo <= hi; `fallback` when the key is absent.
  std::pair<double, double> range(const YAML::Node& map, const char* key, const std::string& what,
                                  std::pair<double, double> fallback) const {
    const YAML::Node n = map[key];
    if (!n) return fallback;
    if (!n.IsSequence() || n.size() != 2) fail(n, what + ": expected [low, high], found " + found(n));
    const std::pair<double, double> r{number(n[0], what + " low"), number(n[1], what + " high")};
    if (r.first > r.second) fail(n, what + ": expected low <= high, found [" + n[0].Scalar() + ", " + n[1].Scalar() + "]");
    return r;
  }

  std::vector<std::string> texts(const YAML::Node& map, const char* key, const std::string& what) const {
    std::vector<std::string> out;
    const YAML::Node n = map[key];
    if (!n) return out;
    if (!n.IsSequence()) fail(n, what + ": expected a list of texts, found " + found(n));
    for (const auto& item : n) out.push_back(text(item, what));
    return out;
  }

  fs::path path(const std::string& p) const {
    const fs::path q(p);
    return fs::absolute(q.is_absolute() ? q : file_.parent_path() / q).lexically_normal();
  }

  void check_keys(const YAML::Node& map, std::initializer_list<const char*> keys, const std::string& what) const {
    for (const auto& kv : map) {
      const std::string k = kv.first.Scalar();
      if (std::none_of(keys.begin(), keys.end(), [&](const char* known) { return k == known; })) {
        std::string list;
        for (const char* known : keys) list += std::string(list.empty() ? "" : ", ") + known;
        fail(kv.first, what + ": unknown key '" + k + "'; expected one of " + list);
      }
    }
  }

 private:
  // The whole scalar as a T, or nullopt.
  template <class T>
  static std::optional<T> parsed(const YAML::Node& n) {
    if (!n.IsScalar()) return std::nullopt;
    const std::string& s = n.Scalar();
    T v{};
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    if (r.ec != std::errc() || r.ptr != s.data() + s.size()) return std::nullopt;
    return v;
  }

  fs::path file_;
};

// The placeholders pose_set may use; any other {word}, or a '{' that no '}' closes, is a mistake in
// the list (it would reach fba-run as it is).
void check_placeholders(const ListReader& r, const YAML::Node& at, const std::string& s) {
  static const std::set<std::string> known = {"mesh", "x", "y", "yaw"};
  for (std::size_t i = s.find('{'); i != std::string::npos; i = s.find('{', i + 1)) {
    if (s.find('}', i) == std::string::npos)
      r.fail(at, "pose_set: expected a placeholder closed by '}' ({mesh}, {x}, {y} or {yaw}); found '" + s.substr(i) + "' unclosed at character " +
                     std::to_string(i + 1) + " of '" + s + "'");
    std::size_t j = i + 1;
    while (j < s.size() && (std::isalpha(static_cast<unsigned char>(s[j])) || s[j] == '_')) ++j;
    if (j == i + 1 || j == s.size() || s[j] != '}') continue;  // not a {word}: a value's own braces
    const std::string word = s.substr(i + 1, j - i - 1);
    if (!known.count(word))
      r.fail(at, "pose_set: unknown placeholder {" + word + "} in '" + s + "'; expected {mesh}, {x}, {y} or {yaw}");
  }
}

// random_runs: per mesh, per_mesh poses drawn uniformly within the ranges, so that a batch can
// measure on poses nobody chose. The draw is mt19937_64's top 53 bits (std::uniform_real_distribution
// differs between standard libraries), rounded to what a list would write by hand.
void add_random_runs(const ListReader& r, const YAML::Node& rr, std::size_t variants, std::vector<RunSpec>& runs) {
  if (!rr.IsMap()) r.fail(rr, "random_runs: expected {meshes, per_mesh, seed, x, y, yaw}, found " + ListReader::found(rr));
  r.check_keys(rr, {"meshes", "per_mesh", "seed", "x", "y", "yaw"}, "random_runs");
  for (const char* key : {"meshes", "per_mesh", "seed"})
    if (!rr[key]) r.fail(rr, std::string("random_runs: expected a key '") + key + "'");
  const std::vector<std::string> meshes = r.texts(rr, "meshes", "random_runs meshes");
  if (meshes.empty()) r.fail(rr["meshes"], "random_runs meshes: expected at least one mesh, found an empty list");
  const std::uint64_t per_mesh = r.whole(rr["per_mesh"], "random_runs per_mesh", 1, 10'000);
  // Counted before any is made (per_mesh and the variants are bounded: no list that fits in memory
  // overflows the product).
  if (const std::uint64_t total = (runs.size() + meshes.size() * per_mesh) * variants; total > kMaxBatchRuns)
    r.fail(rr["per_mesh"], "random_runs: expected at most " + std::to_string(kMaxBatchRuns) + " runs in a batch; found (" +
                               std::to_string(meshes.size()) + " meshes x " + std::to_string(per_mesh) + " poses + " +
                               std::to_string(runs.size()) + " listed runs) x " + std::to_string(variants) + " variant(s) = " +
                               std::to_string(total) + " runs");
  const std::uint64_t seed = r.whole(rr["seed"], "random_runs seed", 0, std::numeric_limits<std::uint64_t>::max());
  const auto x = r.range(rr, "x", "random_runs x", {0, 0}), y = r.range(rr, "y", "random_runs y", {0, 0});
  const auto yaw = r.range(rr, "yaw", "random_runs yaw", {0, 360});
  std::mt19937_64 rng(seed);
  // Rounded to 1 / per_unit; divided, not multiplied by a step, so 0.013 prints as 0.013.
  const auto draw = [&](std::pair<double, double> range, double per_unit) {
    const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;  // [0, 1)
    const double v = std::round((range.first + (range.second - range.first) * u) * per_unit) / per_unit;
    return std::clamp(v, range.first, range.second);
  };
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const std::string path = r.path(meshes[m]).string(), where = r.where(rr["meshes"][m]);
    for (std::uint64_t k = 0; k < per_mesh; ++k) {
      RunSpec s;
      s.mesh = path;
      s.where = where;
      s.x = draw(x, 1000);
      s.y = draw(y, 1000);
      s.yaw = draw(yaw, 1);
      runs.push_back(std::move(s));
    }
  }
}

}  // namespace

BatchList read_list(const std::string& file) {
  BatchList l;
  l.file = fs::absolute(file).lexically_normal();
  if (!fs::is_regular_file(l.file)) throw std::invalid_argument("--batch: the list '" + file + "' is not a readable file");
  ListReader r(l.file);
  YAML::Node root;
  try {
    root = YAML::LoadFile(l.file.string());
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(l.file.string() + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) +
                                ": not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) r.fail(root, "expected a mapping with task, pose_set and runs; found " + ListReader::found(root));
  r.check_no_duplicate_keys(root);
  r.check_keys(root, {"task", "fba_run_args", "timeout_s", "pose_set", "set", "variants", "runs", "random_runs"}, "the list");
  if (!root["task"]) r.fail(root, "expected a key 'task' naming the task file");
  l.task = r.path(r.text(root["task"], "task"));
  if (!fs::is_regular_file(l.task)) r.fail(root["task"], "task: no such file " + l.task.string());
  l.fba_run_args = r.texts(root, "fba_run_args", "fba_run_args");
  if (root["timeout_s"]) {
    l.timeout_s = r.number(root["timeout_s"], "timeout_s");
    if (!(l.timeout_s > 0)) r.fail(root["timeout_s"], "timeout_s: expected seconds > 0");
  }
  l.pose_set = r.texts(root, "pose_set", "pose_set");
  for (std::size_t i = 0; i < l.pose_set.size(); ++i) check_placeholders(r, root["pose_set"][i], l.pose_set[i]);
  l.set = r.texts(root, "set", "set");
  if (const YAML::Node v = root["variants"]) {
    if (!v.IsSequence() || v.size() == 0) r.fail(v, "variants: expected a list of {name, set}, found " + ListReader::found(v));
    if (v.size() > kMaxBatchRuns) r.fail(v, "variants: expected at most " + std::to_string(kMaxBatchRuns) + ", found " + std::to_string(v.size()));
    for (const auto& item : v) {
      if (!item.IsMap()) r.fail(item, "variants: expected {name: ..., set: [...]}, found " + ListReader::found(item));
      r.check_keys(item, {"name", "set"}, "a variant");
      Variant var{r.text(item["name"], "variant name"), r.texts(item, "set", "variant set")};
      // It names the variant's folder under -o: a plain name, which cannot lead out of it.
      if (var.name.find_first_of("/ ") != std::string::npos || var.name == "." || var.name == "..")
        r.fail(item["name"], "variant name: expected a plain folder name (no '/' or space, not '.' or '..'); found '" + var.name + "'");
      for (const auto& other : l.variants)
        if (other.name == var.name) r.fail(item["name"], "variant '" + var.name + "' is given twice");
      l.variants.push_back(std::move(var));
    }
  } else {
    l.variants.push_back({"task", {}});
  }
  const YAML::Node runs = root["runs"];
  if (!runs && !root["random_runs"]) r.fail(root, "expected a key 'runs' (a list of {mesh, pose: [x, y, yaw]}) or 'random_runs'; found neither");
  if (runs && !runs.IsSequence())
    r.fail(runs, "runs: expected a list of {mesh, pose: [x, y, yaw], set: [...]}, found " + ListReader::found(runs));
  if (runs && runs.size() == 0 && !root["random_runs"])
    r.fail(runs, "runs: expected at least one run {mesh, pose: [x, y, yaw]} (or random_runs), found an empty list");
  if (runs && runs.size() * l.variants.size() > kMaxBatchRuns)
    r.fail(runs, "runs: expected at most " + std::to_string(kMaxBatchRuns) + " runs in a batch; found " + std::to_string(runs.size()) +
                     " runs x " + std::to_string(l.variants.size()) + " variant(s)");
  for (const auto& item : runs) {  // an absent 'runs' is an empty sequence here (random_runs only)
    if (!item.IsMap()) r.fail(item, "a run: expected {mesh: ..., pose: [x, y, yaw]}, found " + ListReader::found(item));
    r.check_keys(item, {"mesh", "pose", "set"}, "a run");
    RunSpec s;
    if (!item["mesh"]) r.fail(item, "a run: expected a key 'mesh'");
    s.mesh = r.path(r.text(item["mesh"], "mesh")).string();  // a missing file is that run's row, not the batch's end
    s.where = r.where(item["mesh"]);
    if (const YAML::Node p = item["pose"]) {
      if (!p.IsSequence() || p.size() != 3) r.fail(p, "pose: expected [x, y, yaw] (metres, metres, degrees), found " + ListReader::found(p));
      s.x = r.number(p[0], "pose x");
      s.y = r.number(p[1], "pose y");
      s.yaw = r.number(p[2], "pose yaw");
    }
    s.set = r.texts(item, "set", "run set");
    l.runs.push_back(std::move(s));
  }
  if (const YAML::Node rr = root["random_runs"]) add_random_runs(r, rr, l.variants.size(), l.runs);
  return l;
}

}  // namespace fba::evaluate::batch
