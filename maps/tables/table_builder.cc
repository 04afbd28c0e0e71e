#include "maps/tables/table_builder.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "core/common/parallel.h"
#include "maps/tables/axis_correction.h"

namespace volmap::maps {

namespace {

bool is_three_axis(const VolumetricTable& t) { return t.three_axis_correction(); }

// The model the corrections evaluate: the same errors with positions beyond
// the travel held at the travel end (u + du may leave the travel by a few
// um or urad at a travel end; maps/axis_correction.h does the same).
ErrorModel clamped_model(const ErrorModel& model) {
  return ErrorModel(model.machine(), model.errors(),
                    ModelOptions{model.options().formulation, OutsidePolicy::kClamp});
}

// Five-axis correction of the tables, with what the check needs.
struct PoseCorrection {
  explicit PoseCorrection(const ErrorModel& model)
      : model(clamped_model(model)), solver(this->model, table_correction_options()) {}
  ErrorModel model;
  CorrectionSolver solver;
};

// splitmix64: a stateless hash, so random point p is the same whatever
// thread computes it.
std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

}  // namespace

CorrectionOptions table_correction_options() {
  CorrectionOptions o;
  o.max_iterations = 8;
  o.tolerance_mm = 1e-10;
  o.tolerance_rad = 1e-12;
  return o;
}

void fill_table(const ErrorModel& model, VolumetricTable& table, const BuildOptions& options,
                BuildSummary* summary) {
  const auto t0 = std::chrono::steady_clock::now();
  const bool three_axis = is_three_axis(table);
  std::optional<ThreeAxisCorrection> correction;
  if (three_axis) correction.emplace(model);
  const bool five_axis = table.pose_correction();
  std::optional<PoseCorrection> pose;
  if (five_axis) pose.emplace(model);
  const int du0 = table.correction_channel();
  const int axes = table.axis_count();
  const std::int64_t n0 = table.grid.front().count;
  const std::int64_t nodes = table.node_count();
  const std::int64_t rows_per_layer = nodes / n0;
  const std::int64_t rows = rows_per_layer * table.layer_count();
  const int threads = thread_count(options.threads);
  const int channels = table.channel_count();
  std::vector<std::int64_t> evaluations(static_cast<size_t>(threads), 0);
  std::vector<std::int64_t> clamped(static_cast<size_t>(threads), 0);
  std::vector<std::int64_t> unconverged(static_cast<size_t>(threads), 0);
  std::vector<std::int64_t> singular(static_cast<size_t>(threads), 0);
  std::vector<double> residual(static_cast<size_t>(threads), 0.0);

  parallel_for(
      rows, threads,
      [&](std::int64_t row, int worker) {
        const int layer = static_cast<int>(row / rows_per_layer);
        const std::int64_t first_node = (row % rows_per_layer) * n0;
        const ApproachDirections dir = table.layer_directions(layer);
        AxisVector u = table.node_position(first_node);
        double* out = table.at(layer, first_node);
        std::int64_t evals = 0, clamps = 0, bad = 0, sing = 0;
        double worst = 0.0;
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
          if (five_axis) {
            const CorrectionResult r = pose->solver.correct(u, dir);
            evals += r.iterations + 1;
            if (r.singular) {
              ++sing;
            } else {
              worst = std::max(worst, r.residual_mm);
              bad += !(r.residual_mm <= 1e-9);
            }
            bool beyond = false;
            for (int a = 0; a < axes; ++a) {
              out[du0 + a] = r.du[a];
              const AxisLimits& L = model.machine().limits[static_cast<size_t>(a)];
              const double q = u[a] + r.du[a];
              beyond |= !L.unlimited && (q < L.min || q > L.max);
            }
            clamps += beyond;
          }
        }
        singular[static_cast<size_t>(worker)] += sing;
        residual[static_cast<size_t>(worker)] =
            std::max(residual[static_cast<size_t>(worker)], worst);
        evaluations[static_cast<size_t>(worker)] += evals;
        clamped[static_cast<size_t>(worker)] += clamps;
        unconverged[static_cast<size_t>(worker)] += bad;
      },
      options.progress);

  if (options.repeatability && table.channel("u"))
    fill_uncertainty(model, table, *options.repeatability, threads, options.covariance);

  if (summary != nullptr) {
    summary->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    summary->evaluations = 0;
    summary->correction_clamped = 0;
    summary->correction_unconverged = 0;
    summary->correction_singular = 0;
    summary->correction_max_residual_mm = 0.0;
    for (size_t w = 0; w < evaluations.size(); ++w) {
      summary->correction_singular += singular[w];
      summary->correction_max_residual_mm =
          std::max(summary->correction_max_residual_mm, residual[w]);
      summary->evaluations += evaluations[w];
      summary->correction_clamped += clamped[w];
      summary->correction_unconverged += unconverged[w];
    }
  }
}

VolumetricTable build_table(const ErrorModel& model, const std::vector<double>& spacing,
                            const BuildOptions& options, BuildSummary* summary) {
  VolumetricTable t =
      make_table_layout(model, spacing, options.max_bytes, options.repeatability ? 1 : 0);
  if (options.repeatability) add_uncertainty_channel(t);
  fill_table(model, t, options, summary);
  return t;
}

namespace {

// Check point p of a table (deterministic): the centre of cell p for
// p < cells (when centres are checked), else a pseudo-random point.
void check_point(const VolumetricTable& table, const CheckOptions& options, std::int64_t cells,
                 std::int64_t p, AxisVector& u) {
  const int dims = table.axis_count();
  if (p < cells) {
    std::int64_t rest = p;
    for (int d = 0; d < dims; ++d) {
      const GridAxis& g = table.grid[static_cast<size_t>(d)];
      const std::int64_t i = rest % (g.count - 1);
      rest /= g.count - 1;
      u[d] = 0.5 * (g.node(i) + g.node(i + 1));
    }
    return;
  }
  for (int d = 0; d < dims; ++d) {
    const GridAxis& g = table.grid[static_cast<size_t>(d)];
    const std::uint64_t h = splitmix64(options.seed ^ splitmix64(static_cast<std::uint64_t>(p) * 8 +
                                                                 static_cast<std::uint64_t>(d)));
    const double r = static_cast<double>(h >> 11) * 0x1.0p-53;
    if ((options.at_nodes_mask >> d) & 1u) {
      const std::int64_t k = std::min<std::int64_t>(
          g.count - 1, static_cast<std::int64_t>(r * static_cast<double>(g.count)));
      u[d] = g.node(k);
    } else {
      u[d] = std::min(g.end, g.start + r * (g.end - g.start));
    }
  }
}

}  // namespace

CheckResult check_table(const ErrorModel& model, const VolumetricTable& table,
                        const CheckOptions& options) {
  const bool three_axis = is_three_axis(table) && options.check_correction;
  std::optional<ThreeAxisCorrection> correction;
  if (three_axis) correction.emplace(model);
  const bool five_axis = table.pose_correction() && options.check_correction;
  std::optional<PoseCorrection> pose;
  if (five_axis) pose.emplace(model);
  const bool orientation = table.channel("ei").has_value();
  const int du0 = table.correction_channel();
  const int dims = table.axis_count();
  // Singular band of the five-axis correction: sin(angle(Q, outer axis))
  // below band_sin.
  double band_sin = 0.0;
  Eigen::Vector3d outer_w = Eigen::Vector3d::UnitZ();
  if (five_axis) {
    const Kinematics& kin = pose->solver.kinematics();
    outer_w = kin.outer_axis_w();
    const double h = table.grid[static_cast<size_t>(kin.inner_index())].spacing;
    band_sin = std::sin(std::min(M_PI / 2, options.singular_band_spacings * h));
  }
  std::int64_t cells = 0;
  if (options.cell_centres) {
    cells = 1;
    for (const GridAxis& g : table.grid) cells *= g.count - 1;
  }
  const std::int64_t points = cells + options.random_points;
  const int layers = table.layer_count();
  constexpr std::int64_t kBlock = 4096;
  const std::int64_t blocks = (points * layers + kBlock - 1) / kBlock;
  const int threads = thread_count(options.threads);

  // Per block: the maxima and the first point index reaching the largest
  // (relative to the position maximum's unit: um and urad taken alike).
  struct BlockMax {
    double dv = 0.0, du = 0.0, dq = 0.0, dr = 0.0, worst = -1.0;
    std::int64_t worst_point = -1, excluded = 0;
  };
  std::vector<BlockMax> block_max(static_cast<size_t>(blocks));
  parallel_for(
      blocks, threads,
      [&](std::int64_t block, int) {
        BlockMax bm;
        std::vector<double> interp(static_cast<size_t>(table.channel_count()));
        AxisVector u(dims);
        const std::int64_t end = std::min(points * layers, (block + 1) * kBlock);
        for (std::int64_t item = block * kBlock; item < end; ++item) {
          const int layer = static_cast<int>(item / points);
          const std::int64_t p = item % points;
          check_point(table, options, cells, p, u);
          const ApproachDirections dir = table.layer_directions(layer);
          interpolate(table, u, layer, options.method, OutsidePolicy::kError, interp.data());
          ToolPose nominal;
          const ToolPose actual = model.actual_and_nominal(u, dir, nominal);
          const Eigen::Vector3d dP = actual.tip_mm - nominal.tip_mm;
          const double dv_um =
              Eigen::Vector3d(interp[0] - dP.x(), interp[1] - dP.y(), interp[2] - dP.z()).norm() *
              1e3;
          double dq_urad = 0.0;
          if (orientation) {
            const Eigen::Vector3d dQ = actual.axis - nominal.axis;
            dq_urad =
                Eigen::Vector3d(interp[3] - dQ.x(), interp[4] - dQ.y(), interp[5] - dQ.z()).norm() *
                1e6;
          }
          double du_um = 0.0, dr_urad = 0.0;
          if (three_axis) {
            const Eigen::Vector3d du = correction->solve(u, dir, dP).du_mm;
            du_um =
                Eigen::Vector3d(interp[3] - du.x(), interp[4] - du.y(), interp[5] - du.z()).norm() *
                1e3;
          } else if (five_axis) {
            if (nominal.axis.cross(outer_w).norm() < band_sin) {
              ++bm.excluded;
            } else {
              const CorrectionResult r = pose->solver.correct(u, dir);
              double lin = 0.0, rot = 0.0;
              for (int a = 0; a < dims; ++a) {
                const double e = interp[static_cast<size_t>(du0 + a)] - r.du[a];
                (is_rotary(table.grid[static_cast<size_t>(a)].axis) ? rot : lin) += e * e;
              }
              du_um = std::sqrt(lin) * 1e3;
              dr_urad = std::sqrt(rot) * 1e6;
            }
          }
          bm.dv = std::max(bm.dv, dv_um);
          bm.du = std::max(bm.du, du_um);
          bm.dq = std::max(bm.dq, dq_urad);
          bm.dr = std::max(bm.dr, dr_urad);
          const double worst = std::max(std::max(dv_um, du_um), std::max(dq_urad, dr_urad));
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
    r.max_dq_urad = std::max(r.max_dq_urad, bm.dq);
    r.max_du_rot_urad = std::max(r.max_du_rot_urad, bm.dr);
    r.du_excluded += bm.excluded;
    if (bm.worst > worst) {
      worst = bm.worst;
      worst_point = bm.worst_point;
    }
  }
  r.worst_at = AxisVector(dims);
  for (int d = 0; d < dims; ++d) r.worst_at[d] = table.grid[static_cast<size_t>(d)].start;
  if (worst_point >= 0) check_point(table, options, cells, worst_point, r.worst_at);
  return r;
}

const std::vector<double>& auto_spacing_sequence() {
  static const std::vector<double> s = {100, 50, 25, 20, 10, 5, 2.5, 2, 1, 0.5, 0.25, 0.2, 0.1};
  return s;
}

const std::vector<double>& auto_rotary_spacing_sequence() {
  static const std::vector<double> s = {30, 20, 15, 10, 5, 2.5, 2, 1, 0.5, 0.25, 0.1};
  return s;
}

namespace {

std::vector<double> spacing_of(const Machine& m, double linear_mm, double rotary_rad) {
  std::vector<double> spacing;
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisLimits& L = m.limits[static_cast<size_t>(i)];
    if (is_rotary(m.axis_order[static_cast<size_t>(i)]))
      spacing.push_back(L.unlimited ? rotary_rad : std::min(rotary_rad, L.max - L.min));
    else
      spacing.push_back(std::min(linear_mm, L.max - L.min));
  }
  return spacing;
}

std::string spacing_text(const Machine& m, double linear_mm, double rotary_deg) {
  return m.has_rotary_axes() ? fmt::format("{} mm, {} deg", linear_mm, rotary_deg)
                             : fmt::format("{} mm", linear_mm);
}

}  // namespace

AutoSpacingResult build_for_tolerance(const ErrorModel& model, double tolerance_um,
                                      const CheckOptions& check, const BuildOptions& build,
                                      std::size_t max_bytes, double tolerance_urad) {
  const Machine& m = model.machine();
  const bool rotary = m.has_rotary_axes();
  if (!(tolerance_um > 0.0) || !std::isfinite(tolerance_um))
    throw std::invalid_argument(
        fmt::format("tolerance {} µm is not a positive number", tolerance_um));
  if (rotary && (!(tolerance_urad > 0.0) || !std::isfinite(tolerance_urad)))
    throw std::invalid_argument(
        fmt::format("tolerance {} µrad is not a positive number", tolerance_urad));
  const std::vector<double>& lin = auto_spacing_sequence();
  const std::vector<double>& rot = auto_rotary_spacing_sequence();
  unsigned rotary_mask = 0;
  for (int i = 0; i < m.axis_count(); ++i)
    if (is_rotary(m.axis_order[static_cast<size_t>(i)])) rotary_mask |= 1u << i;
  const unsigned linear_mask = ((1u << m.axis_count()) - 1u) & ~rotary_mask;
  // Error as a fraction of the tolerance (1: at the tolerance).
  auto ratio = [&](const CheckResult& c) {
    double r = c.max_um() / tolerance_um;
    if (rotary) r = std::max(r, c.max_urad() / tolerance_urad);
    return r;
  };
  const int extra = build.repeatability ? 1 : 0;
  double best = std::numeric_limits<double>::infinity();
  std::string best_at;
  size_t li = 0, ri = 0;
  int tried = 0;
  while (li < lin.size() && ri < (rotary ? rot.size() : 1)) {
    const double s_mm = lin[li];
    const double s_deg = rotary ? rot[ri] : 0.0;
    const std::vector<double> spacing = spacing_of(m, s_mm, s_deg * M_PI / 180.0);
    if (table_bytes(model, spacing, extra) > max_bytes) {
      try {
        (void)make_table_layout(model, spacing, max_bytes, extra);  // throws TableTooLarge
      } catch (const TableTooLarge& e) {
        std::string what = e.what();
        what = what.substr(0, what.find("; give a coarser"));
        throw TableTooLarge(fmt::format(
            "automatic spacing for {} µm{}: at {} {} (best so far {:.3g} x the tolerance at {}); "
            "give `spacing`, or raise the tolerance",
            tolerance_um, rotary ? fmt::format(" / {} µrad", tolerance_urad) : "",
            spacing_text(m, s_mm, s_deg), what, best, best_at.empty() ? "none" : best_at));
      }
    }
    AutoSpacingResult r;
    r.table = make_table_layout(model, spacing, max_bytes, extra);
    if (build.repeatability) add_uncertainty_channel(r.table);  // the layout is still empty
    BuildOptions quiet = build;
    quiet.progress = nullptr;     // the search builds many tables: no bar
    quiet.repeatability.reset();  // filled for the chosen table only
    fill_table(model, r.table, quiet, &r.build);
    CheckOptions c = check;
    c.threads = build.threads;
    c.check_correction = !rotary && check.check_correction;  // five-axis: dv decides, du reported
    r.check = check_table(model, r.table, c);
    ++tried;
    const double q = ratio(r.check);
    if (q < best) {
      best = q;
      best_at = spacing_text(m, s_mm, s_deg);
    }
    if (q <= 1.0) {
      if (rotary && check.check_correction) {
        c.check_correction = true;
        r.check = check_table(model, r.table, c);
      }
      r.spacing_mm = s_mm;
      r.spacing_rad = s_deg * M_PI / 180.0;
      r.tables_tried = tried;
      r.table.tolerance_um = tolerance_um;
      r.table.achieved_um = rotary ? r.check.max_dv_um : r.check.max_um();
      r.table.checked_with = c.method;
      if (build.repeatability)
        fill_uncertainty(model, r.table, *build.repeatability, build.threads, build.covariance);
      return r;
    }
    if (!rotary) {
      ++li;
      continue;
    }
    // Which group to refine: each group's own error, the other group's axes
    // at nodes.
    CheckOptions g = c;
    g.cell_centres = false;
    g.random_points = std::max<std::int64_t>(2000, c.random_points / 4);
    g.check_correction = false;
    g.at_nodes_mask = rotary_mask;
    const double q_lin = ratio(check_table(model, r.table, g));
    g.at_nodes_mask = linear_mask;
    const double q_rot = ratio(check_table(model, r.table, g));
    // A group whose own error exceeds the tolerance must be refined; when
    // neither does alone, the one with the larger share.
    bool refine_linear = q_lin > 1.0 || q_lin >= q_rot;
    bool refine_rotary = q_rot > 1.0 || q_rot > q_lin;
    if (refine_linear && li + 1 >= lin.size()) {
      refine_linear = false;
      refine_rotary = true;
    }
    if (refine_rotary && ri + 1 >= rot.size()) {
      refine_rotary = false;
      refine_linear = true;
    }
    if (refine_linear && li + 1 >= lin.size()) break;
    li += refine_linear;
    ri += refine_rotary;
  }
  throw std::invalid_argument(fmt::format(
      "no spacing down to {} reaches {} µm{} with {} interpolation (best: {:.3g} x the tolerance "
      "at {}); raise the tolerance or use `interpolation` cubic",
      spacing_text(m, lin.back(), rot.back()), tolerance_um,
      rotary ? fmt::format(" / {} µrad", tolerance_urad) : "", interpolation_name(check.method),
      best, best_at));
}

}  // namespace volmap::maps
