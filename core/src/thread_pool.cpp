#include "fba/thread_pool.hpp"

#include <algorithm>
#include <atomic>
#include <exception>

namespace fba {

struct ThreadPool::Job {
  const std::function<void(std::size_t)>* fn = nullptr;
  std::size_t n = 0;
  std::atomic<std::size_t> next{0};  // the next index to hand out
  std::mutex mutex;                  // guards done, error
  std::condition_variable finished;
  std::size_t done = 0;
  std::exception_ptr error;
};

ThreadPool::ThreadPool(int threads) {
  for (int i = 0; i < std::max(1, threads); ++i) workers_.emplace_back([this] { worker(); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (auto& t : workers_) t.join();
}

void ThreadPool::work_on(Job& job) {
  for (;;) {
    const std::size_t i = job.next.fetch_add(1);
    if (i >= job.n) return;
    bool failed = false;
    {
      std::lock_guard lock(job.mutex);
      failed = job.error != nullptr;
    }
    std::exception_ptr error;
    if (!failed) {
      try {
        (*job.fn)(i);
      } catch (...) {
        error = std::current_exception();
      }
    }
    std::lock_guard lock(job.mutex);
    if (error && !job.error) job.error = error;
    if (++job.done == job.n) job.finished.notify_all();
  }
}

void ThreadPool::worker() {
  for (;;) {
    std::shared_ptr<Job> job;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !jobs_.empty(); });
      if (jobs_.empty()) return;  // stopping, nothing left
      job = jobs_.front();
      // Every index handed out: nobody else needs to pick this job up.
      if (job->next.load() + 1 >= job->n) jobs_.pop_front();
    }
    work_on(*job);
  }
}

void ThreadPool::parallel_for(std::size_t n, const std::function<void(std::size_t)>& fn) {
  if (n == 0) return;
  auto job = std::make_shared<Job>();
  job->fn = &fn;
  job->n = n;
  if (n > 1) {
    {
      std::lock_guard lock(mutex_);
      jobs_.push_back(job);
    }
    wake_.notify_all();
  }
  work_on(*job);  // the caller works too, so a call from inside fn cannot wait on itself
  {
    std::unique_lock lock(job->mutex);
    job->finished.wait(lock, [&] { return job->done == job->n; });
  }
  {
    std::lock_guard lock(mutex_);  // workers may still hold the job in the queue
    jobs_.erase(std::remove(jobs_.begin(), jobs_.end(), job), jobs_.end());
  }
  if (job->error) std::rethrow_exception(job->error);
}

}  // namespace fba
