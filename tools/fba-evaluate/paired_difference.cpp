#include "paired_difference.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "fba/grasp/object_surface.hpp"

namespace fba::evaluate {

PairedDifference paired_difference(const std::vector<double>& a, const std::vector<double>& b, std::size_t resamples,
                                   std::uint64_t seed) {
  if (a.size() != b.size())
    throw std::invalid_argument("paired_difference: expected one figure per run in both; found " + std::to_string(a.size()) +
                                " and " + std::to_string(b.size()));
  PairedDifference d;
  d.pairs = a.size();
  if (d.pairs == 0) return d;
  std::vector<double> diff(d.pairs);
  for (std::size_t i = 0; i < d.pairs; ++i) {
    diff[i] = b[i] - a[i];
    d.b_higher += diff[i] > 0;
    d.a_higher += diff[i] < 0;
  }
  d.median = grasp::quantile(diff, 0.5);
  d.low = d.high = d.median;
  if (resamples == 0) return d;
  // mt19937_64 is the same sequence on every platform; the index from its top bits (the modulo's
  // bias is below 2^-40 for any batch).
  std::mt19937_64 rng(seed);
  std::vector<double> medians(resamples), draw(d.pairs);
  for (auto& m : medians) {
    for (auto& x : draw) x = diff[rng() % d.pairs];
    m = grasp::quantile(draw, 0.5);
  }
  d.low = grasp::quantile(medians, 0.025);
  d.high = grasp::quantile(medians, 0.975);
  return d;
}

double mcnemar_p(std::size_t only_a, std::size_t only_b) {
  const std::size_t n = only_a + only_b, k = std::min(only_a, only_b);
  if (n == 0) return 1;
  // 2 * P(X <= k) for X ~ Binomial(n, 1/2), the terms in logs (n may be large).
  double tail = 0;
  for (std::size_t i = 0; i <= k; ++i)
    tail += std::exp(std::lgamma(n + 1.0) - std::lgamma(i + 1.0) - std::lgamma(n - i + 1.0) - n * std::log(2.0));
  return std::min(1.0, 2 * tail);
}

}  // namespace fba::evaluate
