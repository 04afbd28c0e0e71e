#include "core/common/parallel.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <limits>
#include <mutex>
#include <thread>
#include <vector>

namespace volmap {

int thread_count(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

namespace {

// The lowest failing item and its exception, from any worker.
struct FirstFailure {
  std::mutex mutex;
  std::int64_t item = std::numeric_limits<std::int64_t>::max();
  std::exception_ptr error;

  void record(std::int64_t failed_item) {
    std::lock_guard<std::mutex> lock(mutex);
    if (failed_item < item) {
      item = failed_item;
      error = std::current_exception();
    }
  }
};

// Items before the failing one may not have run when another thread failed
// first: rerun them in order on this thread so that the reported error is
// the lowest failing item's, whatever the thread count. (Only on failure;
// items are independent and idempotent.)
[[noreturn]] void rethrow_first_in_item_order(const FirstFailure& failure,
                                              const std::function<void(std::int64_t, int)>& work) {
  std::exception_ptr first = failure.error;
  for (std::int64_t item = 0; item < failure.item; ++item) {
    try {
      work(item, 0);
    } catch (...) {
      first = std::current_exception();
      break;
    }
  }
  std::rethrow_exception(first);
}

}  // namespace

void parallel_for(std::int64_t items, int threads,
                  const std::function<void(std::int64_t item, int worker)>& work,
                  const std::function<void(std::int64_t done, std::int64_t items)>& progress) {
  std::atomic<std::int64_t> next{0}, done{0};
  std::atomic<bool> failed{false};
  FirstFailure failure;
  auto run = [&](int worker) {
    while (!failed.load(std::memory_order_relaxed)) {
      const std::int64_t item = next.fetch_add(1, std::memory_order_relaxed);
      if (item >= items) break;
      try {
        work(item, worker);
      } catch (...) {
        failure.record(item);
        failed.store(true);
      }
      done.fetch_add(1, std::memory_order_relaxed);
    }
  };
  threads = static_cast<int>(std::max<std::int64_t>(1, std::min<std::int64_t>(threads, items)));
  std::vector<std::thread> pool;
  pool.reserve(static_cast<size_t>(threads));
  for (int t = 0; t < threads; ++t) pool.emplace_back(run, t);
  if (progress) {
    while (done.load() < items && !failed.load()) {
      progress(done.load(), items);
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  for (std::thread& t : pool) t.join();
  if (failure.error) rethrow_first_in_item_order(failure, work);
  if (progress) progress(items, items);
}

}  // namespace volmap
