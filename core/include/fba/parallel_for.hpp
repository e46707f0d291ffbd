// The one type through which library code (carving, grasp synthesis, exploration) borrows threads
// without depending on who owns them. A component passes its task's pool as one
// (ctx.thread_pool().as_parallel_for()); a test or a tool may pass its own, or none.
#pragma once

#include <cstddef>
#include <functional>

namespace fba {

// Runs f(0) .. f(n - 1), in any order and possibly at once, and returns when all are done,
// rethrowing the first exception of an f. Empty: the library runs them one after another (or on
// threads of its own, where it says so).
using ParallelFor = std::function<void(std::size_t n, const std::function<void(std::size_t)>& f)>;

}  // namespace fba
