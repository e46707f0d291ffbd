// fba-evaluate grasp --batch: a task run by fba-run over a list of objects and poses, in variants
// (the grasp loop and its baselines), each selected grasp evaluated on the true mesh placed as in
// its run, summed up in the grasp issue's table. A run that fails, crashes or hangs is a row with
// its reason; only a bad list or command line stops the tool.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "batch_index.hpp"
#include "fba/geometry/mesh_io.hpp"
#include "fba/grasp/object_surface.hpp"
#include "object_placement.hpp"
#include "grasp_evaluation.hpp"
#include "options.hpp"
#include "paired_difference.hpp"
#include "run_summary.hpp"

extern char** environ;

namespace fba::evaluate {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

const char* kBatchHelp = R"(fba-evaluate grasp --batch: the grasp loop over objects and poses, and its targets' table.

  fba-evaluate grasp --batch LIST.yaml [--jobs N] [-o DIR] [--fba-run PATH] [--random 1000] [--dry-run]

Each run of LIST is run once per variant by fba-run, as a child process writing its own folder
DIR/<variant>/<NN>-<object>/ (summary.json, log.txt, command.txt), with a --run-id of its own that
fba-run writes into summary.json: a summary.json without it (an earlier run's) is refused, the run
is a row "no summary" saying so. The grasp each run selected is placed on the
true mesh, stood where the run stood it, and evaluated (force closure, Ferrari-Canny epsilon:
friction 0.5, 8 cone edges, torque / r_max); each mesh gets --random random contact sets for
comparison. The table (also DIR/table.txt; every run's figures in DIR/runs.json) gives per
variant, per object and overall: runs, % with a grasp selected, % of those force closure, their
median epsilon against the random sets' 99th percentile, % held in the lift test, mean views
until a grasp was selected, wall and CPU seconds per run, and octree nodes processed.

LIST (paths relative to it):
  task: grasp.yaml                     the task file
  fba_run_args: [-e, deterministic]    optional: more fba-run arguments, verbatim
  timeout_s: 600                       optional: a run still going after this is stopped (SIGTERM,
                                       SIGKILL 20 s later) and is a row "timed out"
  pose_set:                            how a run's object and pose reach the task, as --set
    - scene.mesh={mesh}                overrides; {mesh}: the mesh's absolute path, {x} {y}
    - scene.yaw={yaw}                  (metres) {yaw} (degrees): the run's pose
  set: [synthesis.max_views=10]        optional: overrides for every run
  variants:                            optional (default: one, "task"): each run once per variant;
                                       a name is a plain folder name (no '/', not '.' or '..')
    - { name: loop }
    - { name: ring, set: [planner.views=ring, planner.movement_weight=1000, planner.min_gain=0] }
  runs:                                the runs, each as given (runs, random_runs or both)
    - { mesh: ../data/ycb/YcbBanana/model.obj, pose: [0.01, 0, 30], set: [...] }
  random_runs:                         runs at poses drawn at random (after those of runs)
    meshes: [../data/ycb/YcbBanana/model.obj]
    per_mesh: 10                       poses per mesh, drawn uniformly within
    x: [-0.025, 0.025]                 metres (default [0, 0]), rounded to 1 mm
    y: [-0.025, 0.025]                 metres (default [0, 0]), rounded to 1 mm
    yaw: [0, 360]                      degrees (default [0, 360]), rounded to 1 degree
    seed: 2026                         the same seed draws the same poses on any machine
A key given twice in a mapping is refused, and a batch has at most 100000 runs (times variants).
The meshes must be closed (the measure needs the solid's centre of mass); one that is not is refused
before any run.

The pose [x, y, yaw] says where the object stands on the table, in the grasps' frame: the mesh
turned by yaw degrees about z, moved by (x, y) metres and stood on the table at z = 0 (sim.camera's
and sim.hand's object_x, object_y, object_yaw with frame: table).
Each grasp is evaluated on the mesh placed so. Views: the grasp's views when one was selected, else
the views in the carver's model (vision.octree_carver's `updated` events); nodes: the carver's
nodes visited summed over its updates. Components are found by type, not by name. runs.json also
has each run's last carver `detail` (with carver.compare_uniform=true: model_nodes against the
uniform carve's uniform_nodes, and saved_share), however the run ended.

With more than one variant the table ends with each variant paired with the first, run by run:
runs where both, only one or neither selected a grasp (with the exact McNemar test's p on the
runs only one did); the median of the epsilon differences on the mesh over the runs where both
did, and of the node differences over every run, each with a 95% bootstrap interval (10,000
resamples, --seed): a gap whose interval holds 0 is one the runs' spread explains.
--dry-run prints each run's fba-run command line (random poses drawn) and runs nothing.

SIGTERM, SIGINT or SIGHUP to the batch stops it: the running runs get the same signal (and SIGKILL
20 s later), the runs not started are rows "not run", and the table and runs.json are written, their
figures over the runs that finished.

Exit status: 0 when the batch was run and evaluated (whatever the runs' outcomes), 2 for a bad
list or command line, 128 + the signal when it was stopped by one.

Options)";

struct RunSpec {
  std::string mesh;  // absolute
  std::string where;  // the mesh's place in the list, file:line:column
  double x = 0, y = 0, yaw = 0;
  std::vector<std::string> set;
};

// The mesh where the run had it: stood on the table (z = 0) at (x, y), turned by yaw, and laid on
// its side when the run's command line set scene.rest=side (a variant's or the run's own --set),
// exactly as sim.camera and sim.hand place it with frame: table (the grasps' frame). The rest was
// once left out: a run on its side was judged on the mesh standing upright.
TriangleMesh placed_on_table(const RunSpec& r, const std::vector<std::string>& argv) {
  sim_hand::ObjectPlacement p;
  p.x = r.x;
  p.y = r.y;
  p.yaw = r.yaw * std::numbers::pi / 180;
  for (std::size_t i = 0; i + 1 < argv.size(); ++i)
    if (argv[i] == "--set" && argv[i + 1].rfind("scene.rest=", 0) == 0) p.rest = argv[i + 1].substr(11);
  return sim_hand::place_on_table(load_closed_mesh(r.mesh), p);
}

struct Variant {
  std::string name;
  std::vector<std::string> set;
};

struct BatchList {
  fs::path file;
  fs::path task;
  std::vector<std::string> fba_run_args, pose_set, set;
  double timeout_s = 600;
  std::vector<Variant> variants;
  std::vector<RunSpec> runs;
};

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

// The most runs (times variants) a batch may have: at a minute a run, 100,000 runs are 70 days on
// one core; beyond it a list is a mistake, and its runs would be allocated before the first started.
constexpr std::uint64_t kMaxBatchRuns = 100'000;

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

std::string shortest(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
  return s;
}

// One child run: what to start, and how it ended.
struct Job {
  const RunSpec* run = nullptr;
  const Variant* variant = nullptr;
  std::string object;
  fs::path dir;
  std::string run_id;  // given to fba-run, which writes it into summary.json: an older run's summary is not this run's
  std::vector<std::string> argv;
  std::string setup_error;  // the run could not be started, or was not: why
  pid_t pid = -1;
  Clock::time_point started;
  bool term_sent = false, kill_sent = false;
  int stopped_by = 0;  // the signal that stopped the batch before this run ended (passed on to it if it ran)
  int status = 0;
  double elapsed_s = 0, cpu_s = 0;
};

// Builds the job's command line.
void prepare(Job& job, const BatchList& l, const std::string& fba_run) {
  const RunSpec& r = *job.run;
  std::vector<std::string> sets = l.set;
  for (const auto& t : l.pose_set) {
    std::string s = replace_all(t, "{mesh}", r.mesh);
    s = replace_all(s, "{x}", shortest(r.x));
    s = replace_all(s, "{y}", shortest(r.y));
    s = replace_all(s, "{yaw}", shortest(r.yaw));

    sets.push_back(std::move(s));
  }
  sets.insert(sets.end(), job.variant->set.begin(), job.variant->set.end());
  sets.insert(sets.end(), r.set.begin(), r.set.end());
  job.argv = {fba_run, l.task.string(), "-o", job.dir.string(), "--run-id", job.run_id};
  job.argv.insert(job.argv.end(), l.fba_run_args.begin(), l.fba_run_args.end());
  for (const auto& s : sets) job.argv.insert(job.argv.end(), {"--set", s});
}

std::string command_line(const Job& job) {
  std::string line;
  for (const auto& a : job.argv) line += (line.empty() ? "" : " ") + a;
  return line;
}

void start(Job& job) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string log = (job.dir / "log.txt").string();
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  std::vector<char*> argv;
  for (auto& a : job.argv) argv.push_back(a.data());
  argv.push_back(nullptr);
  job.started = Clock::now();
  const int e = posix_spawnp(&job.pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (e != 0) {
    job.pid = -1;
    job.setup_error = "cannot start '" + job.argv[0] + "': " + std::strerror(e) + " (give --fba-run PATH)";
  }
}

// The first SIGTERM, SIGINT or SIGHUP to the batch: runs_all then stops its runs, and the table
// is written for those that finished.
volatile std::sig_atomic_t stop_signal = 0;

void on_stop_signal(int sig) {
  if (!stop_signal) stop_signal = sig;
}

// A signal ignored when the batch started (nohup's SIGHUP) stays ignored.
void catch_stop_signals() {
  for (int sig : {SIGTERM, SIGINT, SIGHUP}) {
    struct sigaction old {};
    sigaction(sig, nullptr, &old);
    if (old.sa_handler == SIG_IGN) continue;
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(sig, &sa, nullptr);
  }
}

std::string signal_name(int sig) {
  return sig == SIGTERM ? "SIGTERM" : sig == SIGINT ? "SIGINT" : sig == SIGHUP ? "SIGHUP" : "signal " + std::to_string(sig);
}

// How long a run stopped in order (a timeout, the batch's own stop) has to write its summary
// before it is killed.
constexpr double kStopGraceS = 20;

// Runs the jobs, at most `parallel` at a time; each line of progress on stderr. When the batch is
// signalled, the running jobs get the same signal and kStopGraceS to end, then SIGKILL; the jobs
// not started are not run. Returns with no child left.
void run_all(std::vector<Job>& jobs, int parallel, double timeout_s) {
  std::size_t next = 0, running = 0, done = 0;
  std::map<pid_t, Job*> by_pid;
  auto progress = [&](const Job& j, const std::string& what) {
    std::fprintf(stderr, "[%zu/%zu] %s %s: %s\n", done, jobs.size(), j.variant->name.c_str(), j.dir.filename().c_str(), what.c_str());
  };
  // Reaps one child that ended, if any; false when none had.
  auto reap = [&](int flags) {
    int status = 0;
    rusage usage{};
    const pid_t pid = wait4(-1, &status, flags, &usage);
    if (pid < 0 && errno != EINTR && errno != ECHILD) throw std::runtime_error(std::string("waiting for fba-run: ") + std::strerror(errno));
    if (pid <= 0 || !by_pid.count(pid)) return false;
    Job& j = *by_pid[pid];
    by_pid.erase(pid);
    --running;
    ++done;
    j.status = status;
    j.elapsed_s = std::chrono::duration<double>(Clock::now() - j.started).count();
    j.cpu_s = usage.ru_utime.tv_sec + usage.ru_stime.tv_sec + 1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
    progress(j, WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status)) : "signal " + std::to_string(WTERMSIG(status)));
    return true;
  };
  while (done < jobs.size() && !stop_signal) {
    while (running < static_cast<std::size_t>(parallel) && next < jobs.size() && !stop_signal) {
      Job& j = jobs[next++];
      if (j.setup_error.empty()) start(j);
      if (!j.setup_error.empty()) {
        ++done;
        progress(j, j.setup_error);
        continue;
      }
      by_pid[j.pid] = &j;
      ++running;
    }
    if (running == 0) continue;
    if (reap(WNOHANG)) continue;
    // A run past its time is asked to stop in order (it then writes its summary), then killed.
    for (auto& [p, j] : by_pid) {
      const double age = std::chrono::duration<double>(Clock::now() - j->started).count();
      if (age > timeout_s && !j->term_sent) {
        kill(p, SIGTERM);
        j->term_sent = true;
      } else if (age > timeout_s + kStopGraceS && !j->kill_sent) {
        kill(p, SIGKILL);
        j->kill_sent = true;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  if (!stop_signal) return;
  const int sig = stop_signal;
  const std::string name = signal_name(sig);
  std::fprintf(stderr, "fba-evaluate grasp --batch: %s: stopping %zu running run(s)\n", name.c_str(), running);
  for (auto& [p, j] : by_pid) {
    kill(p, sig);
    j->stopped_by = sig;
  }
  const auto stopping = Clock::now();
  while (running > 0 && std::chrono::duration<double>(Clock::now() - stopping).count() < kStopGraceS)
    if (!reap(WNOHANG)) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  for (auto& [p, j] : by_pid) {
    kill(p, SIGKILL);
    j->kill_sent = true;
  }
  while (running > 0)
    if (!reap(0) && errno == ECHILD) break;
  for (std::size_t i = next; i < jobs.size(); ++i) {
    jobs[i].stopped_by = sig;
    jobs[i].setup_error = "the batch was stopped by " + name + " before this run started";
  }
}

// What one run gave.
struct Row {
  std::string variant, object, mesh, pose, dir;
  std::string outcome;  // the summary's outcome, or how the child ended without one
  std::string reason;
  bool unfinished = false;  // the batch was stopped before the run ended: left out of the figures
  bool selected = false;
  std::optional<bool> force_closure;
  double epsilon = 0, score = 0;
  std::vector<grasp::ObjectSurface::Placement> contacts;  // the selected grasp's contacts placed on the mesh
  std::optional<bool> held;
  std::string resolved;  // what synthesis had resolved under the fingers: "surface", or "contacts" (after its last view)
  int views = -1;
  double wall_s = -1, cpu_s = -1;
  long long nodes = -1;
  nlohmann::json detail;  // the carver's last `detail` payload (with compare_uniform: against uniform detail), or null
};

std::string last_line(const fs::path& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  return last;
}

std::string clip(std::string s, std::size_t n) {
  for (auto& c : s)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  return s.size() > n ? s.substr(0, n - 3) + "..." : s;
}

// A JSON event payload, or null when it is not JSON.
nlohmann::json payload_json(const nlohmann::json& e) {
  if (!e.contains("payload") || !e["payload"].is_string()) return nullptr;
  return nlohmann::json::parse(e["payload"].get<std::string>(), nullptr, false);
}

// Reads the run's summary.json and evaluates its grasp on the placed mesh.
Row evaluate_job(const Job& j, const grasp::QualityParams& quality) {
  Row row;
  row.variant = j.variant->name;
  row.object = j.object;
  row.mesh = j.run->mesh;
  row.pose = shortest(j.run->x) + " " + shortest(j.run->y) + " " + shortest(j.run->yaw);
  row.dir = j.dir.string();
  row.unfinished = j.stopped_by != 0;
  if (!j.setup_error.empty()) {
    row.outcome = "not run";  // could not start, or the batch was stopped first
    row.reason = j.setup_error;
    return row;
  }
  row.cpu_s = j.cpu_s;
  std::string ended;
  if (WIFSIGNALED(j.status)) ended = std::string("killed by signal ") + std::to_string(WTERMSIG(j.status)) + " (" + strsignal(WTERMSIG(j.status)) + ")";
  if (j.term_sent) ended = "timed out (stopped after the list's timeout_s)" + (ended.empty() ? "" : "; " + ended);
  if (j.stopped_by)
    ended = "interrupted (the batch was stopped by " + signal_name(j.stopped_by) + ", which it passed on)" + (ended.empty() ? "" : "; " + ended);
  // Only this run's own summary counts: one left by an earlier run (the batch removed it, but a
  // run that fails early might not write its own) carries another run_id.
  const fs::path summary = j.dir / "summary.json";
  nlohmann::json s;
  std::string refused;
  if (!fs::exists(summary)) {
    refused = "no summary.json";
  } else if (!fs::is_regular_file(summary)) {  // opening a FIFO would wait for a writer
    refused = "summary.json is " + file_kind(summary) + ", not a regular file";
  } else {
    std::ifstream in(summary);
    s = nlohmann::json::parse(in, nullptr, false);
    if (!s.is_object()) refused = "summary.json is not a JSON object";
    else if (!s.contains("run_id") || !s["run_id"].is_string()) refused = "summary.json is not this run's: no run_id, expected " + j.run_id;
    else if (s["run_id"] != j.run_id) refused = "summary.json is not this run's: run_id " + s["run_id"].get<std::string>() + ", expected " + j.run_id;
    else if (s.value("outcome", "") == "running") refused = "summary.json still says running (fba-run ended before writing its outcome)";
  }
  if (!refused.empty()) {
    row.outcome = j.stopped_by ? "interrupted" : j.term_sent ? "timed out" : WIFSIGNALED(j.status) ? "crashed" : "no summary";
    row.wall_s = j.elapsed_s;
    const std::string said = last_line(j.dir / "log.txt");
    row.reason = (ended.empty() ? "exit " + std::to_string(WEXITSTATUS(j.status)) : ended) + ", " + refused + "; " +
                 (said.empty() ? std::string("log.txt is empty") : "fba-run said: " + said);
    return row;
  }
  row.outcome = s.value("outcome", "?");
  row.wall_s = s.value("wall_time_s", j.elapsed_s);
  row.reason = s.value("reason", "");
  if (!ended.empty()) row.reason = ended + "; " + row.reason;

  // What the components reported (summary.json's results): the task's names are its own, so a
  // result is found by its name; the carver's comparison with uniform refinement (compare_uniform)
  // is its last `detail` event.
  int model_views = -1;
  const nlohmann::json components = s.contains("components") && s["components"].is_object() ? s["components"] : nlohmann::json::object();
  for (const auto& [name, c] : components.items()) {
    if (!c.is_object() || !c.contains("results") || !c["results"].is_object()) continue;
    const auto& r = c["results"];
    if (r.contains("carving") && r["carving"].is_object()) {
      row.nodes = r["carving"].value("nodes_visited", 0LL);
      model_views = r["carving"].value("views", model_views);
    }
    if (r.contains("lift") && r["lift"].is_object()) {
      row.held = r["lift"].value("held", false);
      if (!*row.held) row.reason = "dropped: " + r["lift"].value("reason", std::string("?"));
    }
    if (r.contains("failure") && r["failure"].is_string()) row.reason = "synthesis failed: " + r["failure"].get<std::string>();
    if (r.contains("resolved") && r["resolved"].is_string()) row.resolved = r["resolved"].get<std::string>();
  }
  if (s.contains("events") && s["events"].is_array())
    for (const auto& e : s["events"]) {
      if (!e.is_object() || e.value("name", "") != "detail") continue;
      const auto c = components.find(e.value("source", ""));
      if (c != components.end() && c->is_object() && c->value("type", "") == "vision.octree_carver")
        if (const auto p = payload_json(e); p.is_object()) row.detail = p;
    }
  row.views = model_views;
  if (row.resolved == "contacts") row.reason += (row.reason.empty() ? "" : "; ") + std::string("selected on its contacts alone after the last view");
  try {
    if (const auto g = summary_grasp(s, summary.string())) {
      row.selected = true;
      row.score = g->scores.total;
      if (!g->views.empty()) row.views = static_cast<int>(g->views.size());
      const grasp::ObjectSurface surface(placed_on_table(*j.run, j.argv));
      std::array<GraspContact, 3> placed;
      for (int k = 0; k < 3; ++k) {
        row.contacts.push_back(surface.place(g->contacts[k]));
        placed[k] = row.contacts.back().contact;
      }
      const auto q = surface.evaluate(placed, quality);
      row.force_closure = q.force_closure;
      row.epsilon = q.epsilon;
    }
  } catch (const std::exception& e) {
    row.reason = std::string("grasp not evaluated: ") + e.what() + (row.reason.empty() ? "" : "; " + row.reason);
  }
  return row;
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? NAN : s / v.size();
}

std::string fixed(double v, int decimals, const char* unit = "") {
  if (!std::isfinite(v) || v < 0) return "-";  // no figure (a run that did not start has no time)
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f%s", decimals, v, unit);
  return buf;
}

std::string percent(std::size_t part, std::size_t whole) {
  return whole == 0 ? "-" : fixed(100.0 * part / whole, 0, "%");
}

struct Baseline {
  std::optional<grasp::RandomBaseline> figures;
  std::string error;
};

// The figures of a group of runs (one variant, one object or all).
struct Stats {
  std::size_t runs = 0, selected = 0, evaluated = 0, fc = 0, above = 0, held = 0;
  double median_eps = NAN, views = NAN, wall = NAN, cpu = NAN, nodes = NAN;
};

Stats stats_of(const std::vector<const Row*>& rows, const std::map<std::string, Baseline>& baselines) {
  Stats st;
  st.runs = rows.size();
  std::vector<double> eps, views, wall, cpu, nodes;
  for (const Row* r : rows) {
    if (r->held.value_or(false)) ++st.held;
    if (r->wall_s >= 0) wall.push_back(r->wall_s);
    if (r->cpu_s >= 0) cpu.push_back(r->cpu_s);
    if (r->nodes >= 0) nodes.push_back(static_cast<double>(r->nodes));
    if (!r->selected) continue;
    ++st.selected;
    if (r->views >= 0) views.push_back(r->views);
    if (!r->force_closure) continue;
    ++st.evaluated;
    st.fc += *r->force_closure;
    eps.push_back(r->epsilon);
    const auto b = baselines.find(r->mesh);
    if (b != baselines.end() && b->second.figures && r->epsilon > b->second.figures->epsilon_p99) ++st.above;
  }
  if (!eps.empty()) st.median_eps = grasp::quantile(eps, 0.5);
  st.views = mean(views);
  st.wall = mean(wall);
  st.cpu = mean(cpu);
  st.nodes = mean(nodes);
  return st;
}

// One line of the summary table: the rows of one variant and one object (or all objects).
std::string summary_line(int width, const std::string& variant, const std::string& object, const Stats& st, const Baseline* own) {
  char line[512];
  std::snprintf(line, sizeof line, "%-*s %-18s %4zu %5s %5s %8s %8s %6s %7s %5s %5s %7s %7s %10s", width, variant.c_str(),
                object.c_str(), st.runs, percent(st.selected, st.runs).c_str(), percent(st.fc, st.evaluated).c_str(),
                fixed(st.median_eps, 4).c_str(), own && own->figures ? fixed(own->figures->epsilon_p99, 4).c_str() : "-",
                percent(st.above, st.evaluated).c_str(),
                own && own->figures ? fixed(100 * own->figures->force_closure_share, 1, "%").c_str() : "-",
                percent(st.held, st.runs).c_str(), fixed(st.views, 1).c_str(), fixed(st.wall, 2).c_str(), fixed(st.cpu, 2).c_str(),
                fixed(st.nodes, 0).c_str());
  return line;
}

// Each variant beside the first, run by run (rows are variant by variant, each in the list's run
// order): which runs selected a grasp; the median difference of epsilon on the mesh over the runs
// where both did, and of the nodes processed over every run, with their bootstrap intervals.
std::string paired_block(const BatchList& l, const std::vector<Row>& rows, std::uint64_t seed) {
  constexpr std::size_t kResamples = 10'000;
  const std::size_t n = l.runs.size();
  const std::string& ref = l.variants.front().name;
  int width = 8;
  for (const auto& v : l.variants) width = std::max(width, static_cast<int>(v.name.size()));
  const auto signed_fixed = [](double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%+.*f", decimals, v);
    return std::string(buf);
  };
  std::ostringstream out;
  char line[512];
  out << "\npaired with " << ref << ", run by run (diff: the variant's figure minus " << ref
      << "'s, median over the runs where both selected a grasp for epsilon, over every run for nodes; [95% bootstrap interval]):\n";
  std::snprintf(line, sizeof line, "%-*s %5s %9s %9s %7s %6s %5s %-28s %6s %6s  %s\n", width, "variant", "both", "only_ref", "only_var",
                "neither", "p_sel", "pairs", "eps_diff [interval]", "higher", "lower", "nodes_diff [interval]");
  out << line;
  for (std::size_t v = 1; v < l.variants.size(); ++v) {
    std::size_t both = 0, only_ref = 0, only_var = 0, neither = 0;
    std::vector<double> eps_ref, eps_var, nodes_ref, nodes_var;
    for (std::size_t i = 0; i < n; ++i) {
      const Row& a = rows[i];
      const Row& b = rows[v * n + i];
      if (a.unfinished || b.unfinished) continue;
      if (a.selected && b.selected) ++both;
      else if (a.selected) ++only_ref;
      else if (b.selected) ++only_var;
      else ++neither;
      // Nodes are spent whether or not a grasp comes of them: every run that counted them.
      if (a.nodes >= 0 && b.nodes >= 0) nodes_ref.push_back(static_cast<double>(a.nodes)), nodes_var.push_back(static_cast<double>(b.nodes));
      if (a.selected && b.selected && a.force_closure && b.force_closure) eps_ref.push_back(a.epsilon), eps_var.push_back(b.epsilon);
    }
    const PairedDifference e = paired_difference(eps_ref, eps_var, kResamples, seed);
    const PairedDifference k = paired_difference(nodes_ref, nodes_var, kResamples, seed);
    const std::string eps = e.pairs == 0 ? "-"
                                         : signed_fixed(e.median, 4) + " [" + signed_fixed(e.low, 4) + ", " + signed_fixed(e.high, 4) + "]";
    const std::string nodes =
        k.pairs == 0 ? "-" : signed_fixed(k.median, 0) + " [" + signed_fixed(k.low, 0) + ", " + signed_fixed(k.high, 0) + "]";
    std::snprintf(line, sizeof line, "%-*s %5zu %9zu %9zu %7zu %6.3f %5zu %-28s %6zu %6zu  %s\n", width, l.variants[v].name.c_str(),
                  both, only_ref, only_var, neither, mcnemar_p(only_ref, only_var), e.pairs, eps.c_str(), e.b_higher, e.a_higher,
                  nodes.c_str());
    out << line;
  }
  out << "both, only_ref, only_var, neither: runs where a grasp was selected by both, only " << ref
      << ", only the variant, neither;\np_sel: the exact McNemar test's p on only_ref against only_var (small: the two select "
         "on different shares of runs);\npairs: of both, those evaluated on the mesh; higher, lower: runs where the variant's epsilon "
         "is above, below "
      << ref << "'s.\n";
  return out.str();
}

// `stopped`: how the batch was stopped before its end, if it was.
std::string make_table(const BatchList& l, const std::vector<Row>& rows, const std::map<std::string, Baseline>& baselines,
                       std::size_t random_sets, std::uint64_t seed, const std::string& stopped) {
  std::ostringstream out;
  out << "fba-evaluate grasp --batch " << l.file.filename().string() << ": task " << l.task.filename().string() << ", "
      << l.runs.size() << " runs x " << l.variants.size() << " variant(s); random baseline: " << random_sets
      << " contact sets per mesh\n";
  if (!stopped.empty()) out << stopped << "\n";
  out << "\n";
  // The variant column as wide as the longest name (8 at least).
  int width = 8;
  for (const auto& v : l.variants) width = std::max(width, static_cast<int>(v.name.size()));
  char line[1024];
  std::snprintf(line, sizeof line, "%-*s %-18s %-16s %-10s %5s %4s %7s %5s %7s %7s %9s  %s\n", width, "variant", "object", "pose x y yaw",
                "outcome", "views", "FC", "epsilon", "held", "wall_s", "cpu_s", "nodes", "reason");
  out << line;
  for (const auto& r : rows) {
    std::snprintf(line, sizeof line, "%-*s %-18s %-16s %-10s %5s %4s %7s %5s %7s %7s %9s  %s\n", width, r.variant.c_str(), r.object.c_str(),
                  r.pose.c_str(), r.outcome.c_str(), r.views >= 0 ? std::to_string(r.views).c_str() : "-",
                  !r.selected ? "-" : !r.force_closure ? "?" : *r.force_closure ? "yes" : "no",
                  r.force_closure ? fixed(r.epsilon, 4).c_str() : "-", !r.held ? "-" : *r.held ? "yes" : "no",
                  fixed(r.wall_s, 2).c_str(), fixed(r.cpu_s, 2).c_str(), r.nodes >= 0 ? std::to_string(r.nodes).c_str() : "-",
                  clip(r.reason, 240).c_str());
    out << line;
  }
  out << "\n";
  std::snprintf(line, sizeof line, "%-*s %-18s %4s %5s %5s %8s %8s %6s %7s %5s %5s %7s %7s %10s\n", width, "variant", "object", "runs",
                "grasp", "FC", "med_eps", "rand_p99", ">p99", "rand_FC", "held", "views", "wall_s", "cpu_s", "nodes");
  out << line;
  // Objects in the list's order; the rows of one variant and one object ("" : all objects).
  std::vector<std::string> objects;
  for (const auto& r : rows)
    if (std::find(objects.begin(), objects.end(), r.mesh) == objects.end()) objects.push_back(r.mesh);
  auto group = [&](const std::string& variant, const std::string& mesh) {
    std::vector<const Row*> mine;
    for (const auto& r : rows)
      if (r.variant == variant && (mesh.empty() || r.mesh == mesh) && !r.unfinished) mine.push_back(&r);
    return stats_of(mine, baselines);
  };
  for (const auto& v : l.variants) {
    for (const auto& mesh : objects) {
      const auto b = baselines.find(mesh);
      out << summary_line(width, v.name, object_name(mesh), group(v.name, mesh), b == baselines.end() ? nullptr : &b->second) << "\n";
    }
    out << summary_line(width, v.name, "all", group(v.name, ""), nullptr) << "\n";
  }
  // The variants side by side: the loop beside its baselines.
  if (l.variants.size() > 1) {
    const std::pair<const char*, std::string (*)(const Stats&)> figures[] = {
        {"views", [](const Stats& st) { return fixed(st.views, 1); }},
        {"nodes", [](const Stats& st) { return fixed(st.nodes, 0); }},
        {"FC", [](const Stats& st) { return percent(st.fc, st.evaluated); }},
        {"med_eps", [](const Stats& st) { return fixed(st.median_eps, 4); }},
        {"held", [](const Stats& st) { return percent(st.held, st.runs); }}};
    out << "\nside by side (" ;
    for (std::size_t i = 0; i < l.variants.size(); ++i) out << (i ? " / " : "") << l.variants[i].name;
    out << "):\n";
    std::snprintf(line, sizeof line, "%-18s", "object");
    out << line;
    for (const auto& f : figures) {
      std::snprintf(line, sizeof line, " %-*s", static_cast<int>(9 * l.variants.size()), f.first);
      out << line;
    }
    out << "\n";
    std::vector<std::string> keys = objects;
    keys.push_back("");
    for (const auto& mesh : keys) {
      std::snprintf(line, sizeof line, "%-18s", mesh.empty() ? "all" : object_name(mesh).c_str());
      out << line;
      std::vector<Stats> per;
      for (const auto& v : l.variants) per.push_back(group(v.name, mesh));
      for (const auto& f : figures) {
        out << " ";
        for (const auto& st : per) {
          std::snprintf(line, sizeof line, "%-9s", f.second(st).c_str());
          out << line;
        }
      }
      out << "\n";
    }
  }
  if (l.variants.size() > 1) out << paired_block(l, rows, seed);
  // How far the model's normals are off the object's at the selected contacts: what grasp.synthesis'
  // normal_error_deg is chosen from. Contacts that moved farther than kOnObject were on space the
  // object does not fill; their normals say nothing about the model's surface.
  constexpr double kOnObject = 0.01;
  out << "\nmodel normals at the selected contacts on the object (moved under 1 cm onto the mesh):\n";
  std::snprintf(line, sizeof line, "%-*s %8s %10s %8s %8s %9s\n", width, "variant", "contacts", "median_deg", "p75_deg", "max_deg", "off_mesh");
  out << line;
  for (const auto& v : l.variants) {
    std::vector<double> errors;
    std::size_t off = 0;
    for (const auto& r : rows)
      if (r.variant == v.name && !r.unfinished)
        for (const auto& c : r.contacts) {
          if (c.displacement >= kOnObject) ++off;
          else if (c.normal_error_deg) errors.push_back(*c.normal_error_deg);
        }
    const auto q = [&](double at) { return errors.empty() ? std::string("-") : fixed(grasp::quantile(errors, at), 1); };
    std::snprintf(line, sizeof line, "%-*s %8zu %10s %8s %8s %9zu\n", width, v.name.c_str(), errors.size(), q(0.5).c_str(), q(0.75).c_str(),
                  q(1.0).c_str(), off);
    out << line;
  }
  out << "\ngrasp: runs with a grasp selected; FC: of those, force closure on the true mesh; med_eps: their median epsilon;\n"
         "rand_p99, rand_FC: the random contact sets' 99th percentile of epsilon and force-closure share on the same mesh;\n"
         ">p99: selected grasps whose epsilon is above their mesh's rand_p99; held: runs held through the lift test;\n"
         "views: mean views until the grasp was selected; wall_s: the run's wall time (fba-run's summary), cpu_s: the\n"
         "fba-run process's CPU time, both per run; nodes: mean octree nodes the carver visited per run.\n";
  for (const auto& [mesh, b] : baselines)
    if (!b.error.empty()) out << "random baseline of " << mesh << ": " << b.error << "\n";
  out << "\n";
  // Without the spaces that padding leaves at the ends of lines.
  std::string text;
  std::istringstream lines(out.str());
  for (std::string line; std::getline(lines, line);) {
    line.erase(line.find_last_not_of(' ') + 1);
    text += line + "\n";
  }
  return text;
}

nlohmann::json rows_json(const std::vector<Row>& rows) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& r : rows) {
    nlohmann::json j{{"variant", r.variant}, {"object", r.object}, {"mesh", r.mesh}, {"pose", r.pose}, {"dir", r.dir},
                     {"outcome", r.outcome}, {"reason", r.reason}, {"selected", r.selected}, {"views", r.views},
                     {"wall_s", r.wall_s}, {"cpu_s", r.cpu_s}, {"nodes", r.nodes}};
    if (r.selected) j["score"] = r.score;
    if (r.force_closure) j["force_closure"] = *r.force_closure, j["epsilon"] = r.epsilon;
    for (const auto& c : r.contacts) {
      nlohmann::json k{{"moved_mm", 1000 * c.displacement}};
      if (c.normal_error_deg) k["normal_error_deg"] = *c.normal_error_deg;
      j["contacts"].push_back(k);
    }
    if (r.held) j["held"] = *r.held;
    if (!r.resolved.empty()) j["resolved"] = r.resolved;
    if (!r.detail.is_null()) j["detail"] = r.detail;
    a.push_back(j);
  }
  return a;
}

// fba-run beside this program (the build's or the installed bin folder), else on PATH.
std::string default_fba_run() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec && fs::exists(self.parent_path() / "fba-run")) return (self.parent_path() / "fba-run").string();
  return "fba-run";
}

// Whether `name` (without a '/') is an executable file in a folder of PATH, as posix_spawnp finds it.
bool on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream folders(path ? path : "");
  for (std::string folder; std::getline(folders, folder, ':');) {
    const fs::path p = fs::path(folder.empty() ? "." : folder) / name;
    std::error_code ec;
    if (access(p.c_str(), X_OK) == 0 && !fs::is_directory(p, ec)) return true;
  }
  return false;
}

std::string folder_name(std::size_t index, const std::string& object) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%02zu-", index + 1);
  return buf + object;
}

}  // namespace

int run_grasp_batch(const std::vector<std::string>& args) {
  std::string list_file, out_dir, fba_run = default_fba_run();
  int jobs = 1;
  std::size_t random_sets = 1000;
  std::uint64_t seed = 1;
  bool dry_run = false;
  grasp::QualityParams quality;
  po::options_description opts(kBatchHelp);
  opts.add_options()("help,h", "this help")("batch", po::value(&list_file)->required(), "the list of runs (YAML)")(
      "jobs,j", ranged("jobs", &jobs, 1, 64), "runs at a time")(
      "output,o", po::value(&out_dir), "folder of the runs and the table; default: a new folder under the temporary folder")(
      "fba-run", po::value(&fba_run)->default_value(fba_run), "the fba-run program")(
      "random", ranged("random", &random_sets, std::size_t{0}, kMaxRandomSets), "random contact sets per mesh (0: none)")(
      "seed", ranged("seed", &seed, std::uint64_t{0}, std::numeric_limits<std::uint64_t>::max()), "seed of the random sets and of the paired comparison's bootstrap")(
      "dry-run", po::bool_switch(&dry_run), "print each run's fba-run command line and run nothing");
  po::variables_map vm = parse(args, opts);
  if (vm.count("help")) {
    std::cout << opts << "\n";
    return 0;
  }
  po::notify(vm);
  // Checked before any run, so that a typo does not turn every run into a failed row.
  if (fba_run.find('/') != std::string::npos ? access(fba_run.c_str(), X_OK) != 0 || fs::is_directory(fba_run)
                                             : !on_path(fba_run))
    throw ArgumentError("--fba-run: expected an executable program; found '" + fba_run + "', which is not one");
  if (!out_dir.empty() && fs::exists(out_dir) && !fs::is_directory(out_dir))
    throw ArgumentError("--output: expected a folder; found '" + out_dir + "', which is not one");
  const BatchList list = read_list(list_file);
  // A mesh that is not closed cannot be evaluated: refused before the runs, not after them. One
  // that does not load is left to its runs, whose rows give fba-run's reason.
  std::set<std::string> checked;
  for (const auto& r : list.runs) {
    if (!checked.insert(r.mesh).second || !fs::is_regular_file(r.mesh)) continue;
    try {
      load_closed_mesh(r.mesh);
    } catch (const geometry::MeshLoadError&) {
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(r.where + ": " + e.what());
    }
  }
  if (out_dir.empty() && dry_run) out_dir = (fs::temp_directory_path() / "fba-grasp-batch-XXXXXX").string();
  if (out_dir.empty()) {
    std::string t = (fs::temp_directory_path() / "fba-grasp-batch-XXXXXX").string();
    if (!mkdtemp(t.data())) throw std::runtime_error("cannot create a folder under " + fs::temp_directory_path().string());
    out_dir = t;
  }
  const fs::path out = fs::absolute(out_dir);
  // Each run's id: this batch's random token and the run's number, unique across batches too.
  char token[16];
  std::snprintf(token, sizeof token, "%08x", static_cast<unsigned>(std::random_device{}()));
  std::vector<Job> all;
  for (const auto& v : list.variants)
    for (std::size_t i = 0; i < list.runs.size(); ++i) {
      Job j;
      j.run = &list.runs[i];
      j.variant = &v;
      j.object = object_name(list.runs[i].mesh);
      j.dir = out / v.name / folder_name(i, j.object);
      j.run_id = std::string(token) + "-" + std::to_string(all.size() + 1);
      prepare(j, list, fba_run);
      all.push_back(std::move(j));
    }
  if (dry_run) {
    for (const auto& j : all) std::cout << command_line(j) << "\n";
    return 0;
  }
  std::fprintf(stderr, "fba-evaluate grasp --batch: %zu runs x %zu variant(s) into %s\n", list.runs.size(), list.variants.size(),
               out.c_str());
  catch_stop_signals();
  for (const auto& j : all) {
    fs::create_directories(j.dir);
    fs::remove(j.dir / "summary.json");  // an earlier run's, which must not pass for this run's
    std::ofstream(j.dir / "command.txt") << command_line(j) << "\n";
  }
  run_all(all, jobs, list.timeout_s);

  std::vector<Row> rows;
  for (const auto& j : all) rows.push_back(evaluate_job(j, quality));
  // Per mesh, as the file has it: force closure and epsilon do not change when the whole object
  // and its contacts move together (the pyramids turn with the grasp), so one baseline serves
  // every pose.
  // A stopped batch skips them: it was asked to end.
  std::map<std::string, Baseline> baselines;
  for (const auto& r : list.runs) {
    if (baselines.count(r.mesh) || random_sets == 0 || stop_signal) continue;
    Baseline& b = baselines[r.mesh];
    try {
      b.figures = grasp::random_baseline(grasp::ObjectSurface(load_closed_mesh(r.mesh)), random_sets, seed, quality);
    } catch (const std::exception& e) {
      b.error = e.what();
    }
  }
  std::string stopped;
  if (const int sig = stop_signal) {
    const auto finished = std::count_if(all.begin(), all.end(), [](const Job& j) { return j.pid > 0 && !j.stopped_by; });
    stopped = "stopped by " + signal_name(sig) + ": " + std::to_string(finished) + " of " + std::to_string(all.size()) +
              " runs finished, over which the figures are; the others are rows 'interrupted' (stopped while running) or 'not run'" +
              (random_sets == 0 || baselines.size() == checked.size() ? ""
               : baselines.empty()                                    ? "; no random baseline computed"
                                                                      : "; random baselines not all computed");
  }
  const std::string table = make_table(list, rows, baselines, random_sets, seed, stopped);
  std::cout << table << std::flush;
  std::ofstream(out / "table.txt") << table;
  std::ofstream(out / "runs.json") << rows_json(rows).dump(2) << "\n";
  if (const std::string e = write_batch_index(out, table, rows_json(rows)); !e.empty())
    std::fprintf(stderr, "fba-evaluate grasp --batch: %s\n", e.c_str());
  if (!stopped.empty()) std::fprintf(stderr, "fba-evaluate grasp --batch: %s\n", stopped.c_str());
  // As a program killed by the signal would end, after the table.
  return stop_signal ? 128 + stop_signal : 0;
}

}  // namespace fba::evaluate
