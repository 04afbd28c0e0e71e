#include "maps/table_builder.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>

#include "maps/axis_correction.h"

namespace volmap::maps {

namespace {

int thread_count(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

// Runs work(item, worker) for item in [0, items) on `threads` threads,
// handing out items by an atomic counter. The first exception in item order
// wins (so the error does not depend on the thread count); remaining items
// are skipped. progress (may be empty) is called from this thread.
template <class Work>
void parallel_items(std::int64_t items, int threads, Work&& work,
                    const std::function<void(std::int64_t, std::int64_t)>& progress) {
  std::atomic<std::int64_t> next{0}, done{0};
  std::atomic<bool> failed{false};
  std::mutex error_mutex;
  std::int64_t error_item = std::numeric_limits<std::int64_t>::max();
  std::exception_ptr error;
  auto run = [&](int worker) {
    while (!failed.load(std::memory_order_relaxed)) {
      const std::int64_t item = next.fetch_add(1, std::memory_order_relaxed);
      if (item >= items) break;
      try {
        work(item, worker);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (item < error_item) {
          error_item = item;
          error = std::current_exception();
        }
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
  if (error) {
    // Items before the failing one may not have run when another thread
    // failed first: rerun them in order on this thread so that the reported
    // error is the lowest failing item's, whatever the thread count.
    // (Only on failure; items are independent and idempotent.)
    std::exception_ptr first = error;
    for (std::int64_t item = 0; item < error_item; ++item) {
      try {
        work(item, 0);
      } catch (...) {
        first = std::current_exception();
        break;
      }
    }
    std::rethrow_exception(first);
  }
  if (progress) progress(items, items);
}

bool is_three_axis(const VolumetricTable& t) { return t.channel("ux").has_value(); }

// splitmix64: a stateless hash, so random point p is the same whatever
// thread computes it.
std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

}  // namespace

void fill_table(const ErrorModel& model, VolumetricTable& table, const BuildOptions& options,
                BuildSummary* summary) {
  const auto t0 = std::chrono::steady_clock::now();
  const bool three_axis = is_three_axis(table);
  std::optional<ThreeAxisCorrection> correction;
  if (three_axis) correction.emplace(model);
  const std::int64_t n0 = table.grid.front().count;
  const std::int64_t nodes = table.node_count();
  const std::int64_t rows_per_layer = nodes / n0;
  const std::int64_t rows = rows_per_layer * table.layer_count();
  const int threads = thread_count(options.threads);
  const int channels = table.channel_count();
  std::vector<std::int64_t> evaluations(static_cast<size_t>(threads), 0);
  std::vector<std::int64_t> clamped(static_cast<size_t>(threads), 0);
  std::vector<std::int64_t> unconverged(static_cast<size_t>(threads), 0);

  parallel_items(
      rows, threads,
      [&](std::int64_t row, int worker) {
        const int layer = static_cast<int>(row / rows_per_layer);
        const std::int64_t first_node = (row % rows_per_layer) * n0;
        const ApproachDirections dir = table.layer_directions(layer);
        AxisVector u = table.node_position(first_node);
        double* out = table.at(layer, first_node);
        std::int64_t evals = 0, clamps = 0, bad = 0;
        for (std::int64_t i0 = 0; i0 < n0; ++i0, out += channels) {
          u[0] = table.grid[0].node(i0);
          const PoseError dv = model.exact(u, dir);
          ++evals;
          out[0] = dv.dP_mm.x();
          out[1] = dv.dP_mm.y();
          out[2] = dv.dP_mm.z();
          if (three_axis) {
            const ThreeAxisCorrection::Result r = correction->solve(u, dir, dv.dP_mm);
            evals += r.iterations;
            clamps += r.clamped;
            bad += !r.converged;
            out[3] = r.du_mm.x();
            out[4] = r.du_mm.y();
            out[5] = r.du_mm.z();
          } else {
            out[3] = dv.dQ.x();
            out[4] = dv.dQ.y();
            out[5] = dv.dQ.z();
          }
        }
        evaluations[static_cast<size_t>(worker)] += evals;
        clamped[static_cast<size_t>(worker)] += clamps;
        unconverged[static_cast<size_t>(worker)] += bad;
      },
      options.progress);

  if (options.repeatability && table.channel("u"))
    fill_uncertainty(model, table, *options.repeatability, threads);

  if (summary != nullptr) {
    summary->seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    summary->evaluations = 0;
    summary->correction_clamped = 0;
    summary->correction_unconverged = 0;
    for (size_t w = 0; w < evaluations.size(); ++w) {
      summary->evaluations += evaluations[w];
      summary->correction_clamped += clamped[w];
      summary->correction_unconverged += unconverged[w];
    }
  }
}

VolumetricTable build_table(const ErrorModel& model, const std::vector<double>& spacing,
                            const BuildOptions& options, BuildSummary* summary) {
  VolumetricTable t = make_table_layout(model, spacing);
  if (options.repeatability) add_uncertainty_channel(t);
  fill_table(model, t, options, summary);
  return t;
}

CheckResult check_table(const ErrorModel& model, const VolumetricTable& table,
                        const CheckOptions& options) {
  const bool three_axis = is_three_axis(table) && options.check_correction;
  std::optional<ThreeAxisCorrection> correction;
  if (three_axis) correction.emplace(model);
  const int dims = table.axis_count();
  std::int64_t cells = 1;
  for (const GridAxis& g : table.grid) cells *= g.count - 1;
  const std::int64_t points = cells + options.random_points;
  const int layers = table.layer_count();
  constexpr std::int64_t kBlock = 4096;
  const std::int64_t blocks = (points * layers + kBlock - 1) / kBlock;
  const int threads = thread_count(options.threads);

  // Per block: max dv, max du and the first point index reaching the larger.
  struct BlockMax {
    double dv = 0.0, du = 0.0, worst = -1.0;
    std::int64_t worst_point = -1;
  };
  std::vector<BlockMax> block_max(static_cast<size_t>(blocks));
  parallel_items(
      blocks, threads,
      [&](std::int64_t block, int) {
        BlockMax bm;
        std::vector<double> interp(static_cast<size_t>(table.channel_count()));
        AxisVector u(dims);
        const std::int64_t end = std::min(points * layers, (block + 1) * kBlock);
        for (std::int64_t item = block * kBlock; item < end; ++item) {
          const int layer = static_cast<int>(item / points);
          const std::int64_t p = item % points;
          if (p < cells) {  // centre of cell p
            std::int64_t rest = p;
            for (int d = 0; d < dims; ++d) {
              const GridAxis& g = table.grid[static_cast<size_t>(d)];
              const std::int64_t i = rest % (g.count - 1);
              rest /= g.count - 1;
              u[d] = 0.5 * (g.node(i) + g.node(i + 1));
            }
          } else {
            for (int d = 0; d < dims; ++d) {
              const GridAxis& g = table.grid[static_cast<size_t>(d)];
              const std::uint64_t h = splitmix64(options.seed ^ splitmix64(
                  static_cast<std::uint64_t>(p) * 8 + static_cast<std::uint64_t>(d)));
              const double r = static_cast<double>(h >> 11) * 0x1.0p-53;
              u[d] = std::min(g.end, g.start + r * (g.end - g.start));
            }
          }
          const ApproachDirections dir = table.layer_directions(layer);
          interpolate(table, u, layer, options.method, OutsidePolicy::kError, interp.data());
          const PoseError dv = model.exact(u, dir);
          const Eigen::Vector3d e_dv(interp[0] - dv.dP_mm.x(), interp[1] - dv.dP_mm.y(),
                                     interp[2] - dv.dP_mm.z());
          const double dv_um = e_dv.norm() * 1e3;
          double du_um = 0.0;
          if (three_axis) {
            const Eigen::Vector3d du = correction->solve(u, dir, dv.dP_mm).du_mm;
            du_um = Eigen::Vector3d(interp[3] - du.x(), interp[4] - du.y(), interp[5] - du.z())
                        .norm() * 1e3;
          }
          bm.dv = std::max(bm.dv, dv_um);
          bm.du = std::max(bm.du, du_um);
          const double worst = std::max(dv_um, du_um);
          if (worst > bm.worst) {
            bm.worst = worst;
            bm.worst_point = p;
          }
        }
        block_max[static_cast<size_t>(block)] = bm;
      },
      {});

  CheckResult r;
  r.points = points;
  double worst = -1.0;
  std::int64_t worst_point = -1;
  for (const BlockMax& bm : block_max) {  // in block order: deterministic ties
    r.max_dv_um = std::max(r.max_dv_um, bm.dv);
    r.max_du_um = std::max(r.max_du_um, bm.du);
    if (bm.worst > worst) {
      worst = bm.worst;
      worst_point = bm.worst_point;
    }
  }
  // Position of the worst point (recomputed, same formula as above).
  r.worst_at = AxisVector(dims);
  for (int d = 0; d < dims; ++d) r.worst_at[d] = table.grid[static_cast<size_t>(d)].start;
  if (worst_point >= 0) {
    std::int64_t rest = worst_point;
    for (int d = 0; d < dims; ++d) {
      const GridAxis& g = table.grid[static_cast<size_t>(d)];
      if (worst_point < cells) {
        const std::int64_t i = rest % (g.count - 1);
        rest /= g.count - 1;
        r.worst_at[d] = 0.5 * (g.node(i) + g.node(i + 1));
      } else {
        const std::uint64_t h = splitmix64(options.seed ^ splitmix64(
            static_cast<std::uint64_t>(worst_point) * 8 + static_cast<std::uint64_t>(d)));
        const double x = static_cast<double>(h >> 11) * 0x1.0p-53;
        r.worst_at[d] = std::min(g.end, g.start + x * (g.end - g.start));
      }
    }
  }
  return r;
}

const std::vector<double>& auto_spacing_sequence() {
  static const std::vector<double> s = {100, 50, 25, 20, 10, 5, 2.5, 2, 1, 0.5, 0.25, 0.2, 0.1};
  return s;
}

AutoSpacingResult build_for_tolerance(const ErrorModel& model, double tolerance_um,
                                      const CheckOptions& check, const BuildOptions& build,
                                      std::size_t max_bytes) {
  const Machine& m = model.machine();
  if (m.has_rotary_axes())
    throw std::invalid_argument(
        "automatic spacing (--tolerance-um) is for three-axis machines; give --spacing for "
        "machines with rotary axes");
  if (!(tolerance_um > 0.0) || !std::isfinite(tolerance_um))
    throw std::invalid_argument(fmt::format("tolerance {} um is not a positive number", tolerance_um));
  double best_um = std::numeric_limits<double>::infinity();
  double best_spacing = 0.0;
  for (double s : auto_spacing_sequence()) {
    std::vector<double> spacing;
    for (int i = 0; i < m.axis_count(); ++i) {
      const AxisLimits& L = m.limits[static_cast<size_t>(i)];
      spacing.push_back(std::min(s, L.max - L.min));
    }
    VolumetricTable layout = make_table_layout(model, spacing);
    if (build.repeatability) add_uncertainty_channel(layout);
    if (layout.size_bytes() > max_bytes) break;
    AutoSpacingResult r;
    r.table = std::move(layout);
    BuildOptions quiet = build;
    quiet.progress = nullptr;  // the search builds many tables: no bar
    quiet.repeatability.reset();  // filled for the chosen table only
    fill_table(model, r.table, quiet, &r.build);
    CheckOptions c = check;
    c.threads = build.threads;
    r.check = check_table(model, r.table, c);
    if (r.check.max_um() < best_um) {
      best_um = r.check.max_um();
      best_spacing = s;
    }
    if (r.check.max_um() <= tolerance_um) {
      r.spacing_mm = s;
      r.table.tolerance_um = tolerance_um;
      r.table.achieved_um = r.check.max_um();
      r.table.checked_with = c.method;
      if (build.repeatability) fill_uncertainty(model, r.table, *build.repeatability, build.threads);
      return r;
    }
  }
  throw std::invalid_argument(fmt::format(
      "no spacing down to {} mm reaches {} um with {} interpolation (best: {:.3g} um at {} mm); "
      "raise --tolerance-um or use --interpolation cubic",
      auto_spacing_sequence().back(), tolerance_um, interpolation_name(check.method), best_um,
      best_spacing));
}

}  // namespace volmap::maps
