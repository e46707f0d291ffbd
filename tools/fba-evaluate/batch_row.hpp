// What one run of a batch gave: its outcome and reason as its own summary.json says them (or how
// the child ended without one), its figures, and its selected grasp evaluated on the true mesh.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "batch_jobs.hpp"
#include "fba/grasp/grasp_quality.hpp"
#include "fba/grasp/object_surface.hpp"

namespace fba::evaluate::batch {

// What one run gave.
struct Row {
  std::string variant, object, mesh, pose, dir;
  std::string outcome;  // the summary's outcome, or how the child ended without one
  std::string reason;
  bool unfinished = false;  // the batch was stopped before the run ended: left out of the figures
  bool selected = false;
  // The selected grasp on the true mesh, each contact along its normal and at its closest point;
  // force_closure and epsilon are the worse placement's ("force closure on the true mesh").
  std::optional<grasp::GraspOnSurface> on_mesh;
  std::optional<bool> force_closure;
  double epsilon = 0, score = 0;
  std::optional<bool> held;
  std::string resolved;  // what synthesis had resolved under the fingers: "surface", or "contacts" (after its last view)
  int views = -1;
  double wall_s = -1, cpu_s = -1;
  std::vector<double> synthesis_s;  // synthesis's wall seconds on each view (its result seconds_per_view)
  long long nodes = -1;
  nlohmann::json detail;  // the carver's last `detail` payload (with compare_uniform: against uniform detail), or null
};

// Reads the run's summary.json and evaluates its grasp on the placed mesh.
Row evaluate_job(const Job& j, const grasp::QualityParams& quality);

}  // namespace fba::evaluate::batch
