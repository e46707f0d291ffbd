// fba-evaluate grasp --batch: a task run by fba-run over a list of objects and poses, in variants
// (the grasp loop and its baselines), each selected grasp evaluated on the true mesh placed as in
// its run, summed up in the grasp issue's table. A run that fails, crashes or hangs is a row with
// its reason; only a bad list or command line stops the tool. This file holds the command line and
// its order of work; the parts are batch_list (the list), batch_jobs (the runs as child processes),
// batch_row (what a run gave), batch_stats and batch_table (the figures and the table).
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <boost/program_options.hpp>
#include <nlohmann/json.hpp>

#include "batch_index.hpp"
#include "batch_jobs.hpp"
#include "batch_list.hpp"
#include "batch_row.hpp"
#include "batch_table.hpp"
#include "fba/geometry/mesh_io.hpp"
#include "fba/grasp/object_surface.hpp"
#include "grasp_evaluation.hpp"
#include "options.hpp"

namespace fba::evaluate {
namespace {

namespace fs = std::filesystem;
using namespace batch;

const char* kBatchHelp = R"(fba-evaluate grasp --batch: the grasp loop over objects and poses, and its targets' table.

  fba-evaluate grasp --batch LIST.yaml [--jobs N] [-o DIR] [--fba-run PATH] [--random 1000] [--dry-run]

Each run of LIST is run once per variant by fba-run, as a child process writing its own folder
DIR/<variant>/<NN>-<object>/ (summary.json, log.txt, command.txt), with a --run-id of its own that
fba-run writes into summary.json: a summary.json without it (an earlier run's) is refused, the run
is a row "no summary" saying so. The grasp each run selected is placed on the
true mesh, stood where the run stood it, two ways: each contact along its normal line, and each at
its closest surface point (on an edge the two land on different faces). Each placement is evaluated
(force closure, Ferrari-Canny epsilon: friction 0.5, 8 cone edges, torque / r_max) and the grasp
counts as the worse of the two (FC_n/c gives both; runs.json's "placements" each contact of both);
each mesh gets --random random contact sets for comparison. The table (also DIR/table.txt; every
run's figures in DIR/runs.json) gives per variant, per object and overall: runs, % with a grasp
selected, % of those force closure, their median epsilon against the random sets' 99th
percentile, % held in the lift test, mean views until a grasp was selected, wall and CPU seconds
per run, octree nodes processed, and the grasps the two placements split on.

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
