// How two variants of a batch compare on the same runs: the median of their per-run differences
// with a bootstrap interval, so that "the same quality" can be told from a gap the runs' spread
// explains (a dozen runs differ by chance more than their medians suggest).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace fba::evaluate {

struct PairedDifference {
  std::size_t pairs = 0;
  double median = 0;         // the median of b[i] - a[i]
  double low = 0, high = 0;  // its 95% percentile-bootstrap interval
  std::size_t b_higher = 0, a_higher = 0;
};

// a and b hold one figure per run, in the same order (the same run at the same index); throws
// std::invalid_argument when their lengths differ. `resamples` draws of the pairs with replacement
// (seeded: the same inputs give the same interval); with no pairs every figure is 0.
PairedDifference paired_difference(const std::vector<double>& a, const std::vector<double>& b, std::size_t resamples,
                                   std::uint64_t seed);

// Whether two variants select a grasp on the same runs equally often: the exact two-sided McNemar
// test on the runs where only one did (only_a, only_b), the chance of a split at least that uneven
// if either were as likely to be the one. 1 when no run tells them apart.
double mcnemar_p(std::size_t only_a, std::size_t only_b);

}  // namespace fba::evaluate
