// Data-parallel loops over a ParallelFor (fba/parallel_for.hpp): one call per index for a few
// costly items (thumbs, views, hulls), chunks for many cheap ones (the task's pool hands out one
// index at a time under a lock, too costly per surface sample).
#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>

#include "fba/grasp/synthesis.hpp"

namespace fba::grasp {

// f(i) for every i in [0, n), at once when parallel_for is given.
inline void for_each_index(const ParallelFor& parallel_for, std::size_t n, const std::function<void(std::size_t)>& f) {
  if (parallel_for) return parallel_for(n, f);
  for (std::size_t i = 0; i < n; ++i) f(i);
}

// f(begin, end) over [0, n) in at most 32 contiguous chunks, at once when parallel_for is given.
template <class F>
void for_each_chunk(const ParallelFor& parallel_for, std::size_t n, F&& f) {
  if (!parallel_for || n < 64) {
    f(std::size_t{0}, n);
    return;
  }
  const std::size_t chunks = std::min<std::size_t>(32, n);
  parallel_for(chunks, [&](std::size_t c) { f(c * n / chunks, (c + 1) * n / chunks); });
}

}  // namespace fba::grasp
