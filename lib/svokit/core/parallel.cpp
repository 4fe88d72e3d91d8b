#include "svokit/core/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <set>
#include <system_error>
#include <thread>
#include <vector>

#include <sched.h>

namespace svokit {
namespace {

using parallel_detail::FunctionRef;

// A piece of parallel work that the pool's threads help its caller with. The caller owns it and
// retires it (Pool::Retire) before it goes: helpers join and leave under the pool's lock.
class Job {
 public:
  virtual ~Job() = default;
  /// Claims and runs one piece of work; false when none can be claimed now.
  virtual bool RunOne() = 0;
  /// Whether RunOne would claim a piece now.
  virtual bool Claimable() const = 0;
  /// No piece is claimed after this (a task threw, or the caller is leaving early).
  virtual void Stop() = 0;

  std::size_t helpers = 0;          // pool threads working on it (under the pool's lock)
  std::size_t most_helpers = 0;     // the thread limit when it was posted, less its caller
  std::exception_ptr helper_error;  // the first exception a helper's piece threw
};

// Threads started on demand, never more than the cores less one (the caller is the other), kept
// for the process's lifetime: they sleep when no job wants them. A job takes at most the limit
// less one of them, so ThreadLimit(1) runs everything on the caller.
class Pool {
 public:
  static Pool& Get() {
    static Pool* const pool = new Pool;  // never destroyed: workers may outlive static objects
    return *pool;
  }

  std::size_t cores() const { return cores_; }

  std::size_t Limit() {
    const std::lock_guard lock(mutex_);
    return LimitLocked();
  }
  void AddLimit(std::size_t threads) {
    const std::lock_guard lock(mutex_);
    limits_.insert(threads);
  }
  void RemoveLimit(std::size_t threads) {
    const std::lock_guard lock(mutex_);
    limits_.erase(limits_.find(threads));
  }

  /// Offers `job` to the workers, as many as the limit allows; false (nothing posted) when the
  /// limit is 1 thread.
  bool Post(Job& job) {
    {
      const std::lock_guard lock(mutex_);
      job.most_helpers = LimitLocked() - 1;
      if (job.most_helpers == 0) return false;
      StartWorkers(job.most_helpers);
      jobs_.push_back(&job);
    }
    wake_.notify_all();
    return true;
  }
  /// Takes `job` back: no worker joins it after this, and the ones in it have left on return.
  void Retire(Job& job) {
    std::unique_lock lock(mutex_);
    jobs_.erase(std::find(jobs_.begin(), jobs_.end(), &job));
    left_.wait(lock, [&] { return job.helpers == 0; });
  }
  /// Wakes the workers: a posted job has pieces to claim again.
  void Wake() {
    { const std::lock_guard lock(mutex_); }  // a worker testing for work sees it or is waiting
    wake_.notify_all();
  }

 private:
  Pool() : cores_(Cores()) {}

  static std::size_t Cores() {
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0) {
      return std::max(1, CPU_COUNT(&set));
    }
    return std::max(1u, std::thread::hardware_concurrency());
  }

  std::size_t LimitLocked() const {
    const std::size_t limit = limits_.empty() ? cores_ : *limits_.begin();
    return std::clamp<std::size_t>(limit, 1, cores_);
  }

  void StartWorkers(std::size_t wanted) {
    while (workers_ < wanted) {
      try {
        std::thread([this] { Work(); }).detach();
      } catch (const std::system_error&) {
        return;  // no thread to be had: the callers do the work
      }
      ++workers_;
    }
  }

  Job* ClaimableJob() const {
    for (Job* job : jobs_) {
      if (job->helpers < job->most_helpers && job->Claimable()) return job;
    }
    return nullptr;
  }

  void Work() {
    std::unique_lock lock(mutex_);
    for (;;) {
      Job* job = nullptr;
      wake_.wait(lock, [&] { return (job = ClaimableJob()) != nullptr; });
      ++job->helpers;
      lock.unlock();
      std::exception_ptr error;
      try {
        while (job->RunOne()) {
        }
      } catch (...) {
        error = std::current_exception();
        job->Stop();
      }
      lock.lock();
      if (error && !job->helper_error) job->helper_error = error;
      if (--job->helpers == 0) left_.notify_all();
    }
  }

  const std::size_t cores_;
  std::mutex mutex_;
  std::condition_variable wake_, left_;
  std::vector<Job*> jobs_;  // the oldest first
  std::multiset<std::size_t> limits_;
  std::size_t workers_ = 0;
};

// Posts a job for its lifetime: on leaving, early or not, it stops and retires the job, then
// rethrows what a helper threw.
class Posted {
 public:
  explicit Posted(Job& job) : job_(job), posted_(Pool::Get().Post(job)) {}
  ~Posted() {
    if (posted_) {
      job_.Stop();
      Pool::Get().Retire(job_);
    }
  }
  Posted(const Posted&) = delete;
  Posted& operator=(const Posted&) = delete;
  /// Retires the job and rethrows a helper's exception (a destructor may not throw).
  void Finish() {
    if (!posted_) return;
    posted_ = false;
    Pool::Get().Retire(job_);
    if (job_.helper_error) std::rethrow_exception(job_.helper_error);
  }

 private:
  Job& job_;
  bool posted_;
};

// Tasks 0 .. count − 1, claimed one at a time in index order.
class TasksJob final : public Job {
 public:
  TasksJob(std::size_t count, FunctionRef<void(std::size_t)> task) : count_(count), task_(task) {}
  bool RunOne() override {
    const std::size_t i = next_.fetch_add(1, std::memory_order_relaxed);
    if (i >= count_) return false;
    task_(i);
    return true;
  }
  bool Claimable() const override { return next_.load(std::memory_order_relaxed) < count_; }
  void Stop() override { next_.store(count_, std::memory_order_relaxed); }

 private:
  const std::size_t count_;
  const FunctionRef<void(std::size_t)> task_;
  std::atomic<std::size_t> next_{0};
};

// Items made by any thread into a ring of slots, taken in order by the caller alone.
class InOrderJob final : public Job {
 public:
  InOrderJob(std::size_t first, std::size_t end, std::size_t slots,
             FunctionRef<void(std::size_t, std::size_t)> make,
             FunctionRef<Status(std::size_t)> take)
      : end_(end), make_(make), take_(take), next_make_(first), next_take_(first), ready_(slots) {}

  bool RunOne() override {
    std::size_t i;
    {
      const std::lock_guard lock(mutex_);
      if (!ClaimableLocked()) return false;
      i = next_make_++;
    }
    make_(i, i % ready_.size());
    {
      const std::lock_guard lock(mutex_);
      ready_[i % ready_.size()] = true;
    }
    made_.notify_all();
    return true;
  }
  bool Claimable() const override {
    const std::lock_guard lock(mutex_);
    return ClaimableLocked();
  }
  void Stop() override {
    {
      const std::lock_guard lock(mutex_);
      stopped_ = true;
    }
    made_.notify_all();  // the caller waits for nothing more
  }

  /// The caller's part: takes each item as soon as it is made, and makes items itself while the
  /// next one is not claimed yet.
  Status TakeAll() {
    std::unique_lock lock(mutex_);
    while (next_take_ < end_ && !stopped_) {
      const std::size_t slot = next_take_ % ready_.size();
      if (ready_[slot]) {
        lock.unlock();
        Status taken = take_(slot);
        lock.lock();
        ready_[slot] = false;
        ++next_take_;
        if (!taken.ok()) return taken;
        lock.unlock();
        Pool::Get().Wake();  // a slot is free: helpers that found none may claim again
        lock.lock();
      } else if (ClaimableLocked()) {
        lock.unlock();
        RunOne();
        lock.lock();
      } else {
        made_.wait(lock);
      }
    }
    return {};
  }

 private:
  bool ClaimableLocked() const {
    return !stopped_ && next_make_ < end_ && next_make_ < next_take_ + ready_.size();
  }

  const std::size_t end_;
  const FunctionRef<void(std::size_t, std::size_t)> make_;
  const FunctionRef<Status(std::size_t)> take_;
  mutable std::mutex mutex_;
  std::condition_variable made_;
  std::size_t next_make_, next_take_;
  std::vector<bool> ready_;
  bool stopped_ = false;
};

}  // namespace

namespace parallel_detail {

void RunTasks(std::size_t count, FunctionRef<void(std::size_t)> task) {
  if (count <= 1) {
    if (count == 1) task(0);
    return;
  }
  TasksJob job(count, task);
  Posted posted(job);
  while (job.RunOne()) {
  }
  posted.Finish();
}

Status RunInOrder(std::size_t first, std::size_t end, std::size_t slots,
                  FunctionRef<void(std::size_t, std::size_t)> make,
                  FunctionRef<Status(std::size_t)> take) {
  InOrderJob job(first, end, std::max<std::size_t>(slots, 1), make, take);
  Posted posted(job);
  Status taken = job.TakeAll();
  job.Stop();  // after an error: nothing more is made
  posted.Finish();
  return taken;
}

}  // namespace parallel_detail

std::size_t Concurrency() {
  return Pool::Get().Limit();
}

PoolThreadLimit::PoolThreadLimit(std::size_t threads)
    : threads_(threads == 0 ? Pool::Get().cores() : threads) {
  Pool::Get().AddLimit(threads_);
}

PoolThreadLimit::~PoolThreadLimit() {
  Pool::Get().RemoveLimit(threads_);
}

}  // namespace svokit
