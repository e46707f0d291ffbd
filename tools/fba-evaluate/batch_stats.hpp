// The figures of a group of a batch's runs (one variant, one object or all) and how the tables
// print a figure that may be missing.
#pragma once

#include <cmath>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "batch_row.hpp"
#include "fba/grasp/object_surface.hpp"

namespace fba::evaluate::batch {

// The mean, NaN for none.
double mean(const std::vector<double>& v);

// v with `decimals` decimals and `unit`; "-" for no figure (NaN or negative: a run that did not
// start has no time).
std::string fixed(double v, int decimals, const char* unit = "");

// part of whole as a whole percentage; "-" when whole is 0.
std::string percent(std::size_t part, std::size_t whole);

struct Baseline {
  std::optional<grasp::RandomBaseline> figures;
  std::string error;
};

// The figures of a group of runs (one variant, one object or all).
struct Stats {
  std::size_t runs = 0, selected = 0, evaluated = 0, fc = 0, above = 0, held = 0;
  std::size_t split = 0;  // evaluated grasps whose two placements on the mesh disagree on force closure
  double median_eps = NAN, views = NAN, wall = NAN, cpu = NAN, nodes = NAN;
  double synthesis_s = NAN;  // the median of synthesis's seconds on one view, over every view of the runs
};

Stats stats_of(const std::vector<const Row*>& rows, const std::map<std::string, Baseline>& baselines);

}  // namespace fba::evaluate::batch
