// One thread pool for the loops whose items are independent (the map
// builder's rows and check blocks, the per-node uncertainty): items are
// handed out by an atomic counter, so each item's result is the same
// whatever the thread count or the machine (docs/hardening.md, determinism).
#pragma once

#include <cstdint>
#include <functional>

namespace volmap {

/// `requested` when positive, else the hardware's thread count (at least 1).
int thread_count(int requested);

/// Runs work(item, worker) for every item in [0, items) on
/// min(threads, items) threads (at least one), worker in [0, threads).
/// The first exception in item order is rethrown in the caller (so the error
/// does not depend on the thread count); the items after a failure are
/// skipped. Items must be independent and idempotent: on a failure, the
/// items before the failing one run again, in order, on the calling thread.
/// progress(done, items), when given, is called from the calling thread
/// while the work runs and once at the end.
void parallel_for(std::int64_t items, int threads,
                  const std::function<void(std::int64_t item, int worker)>& work,
                  const std::function<void(std::int64_t done, std::int64_t items)>& progress = {});

}  // namespace volmap
