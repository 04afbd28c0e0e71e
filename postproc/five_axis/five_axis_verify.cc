#include "postproc/five_axis/five_axis_verify.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "core/common/golden_section.h"
#include "core/common/input_error.h"
#include "core/common/internal_error.h"
#include "core/common/units.h"
#include "gcode/nc_path.h"
#include "postproc/five_axis/five_axis_post.h"
#include "postproc/five_axis/five_axis_transform.h"

namespace volmap::post {
namespace {

using Eigen::Vector3d;

constexpr size_t kWindow = 24;  ///< nominal moves searched ahead of the cursor

double angle_between(const Vector3d& a, const Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

struct NominalMove {
  FiveAxisMove m;
  int line = 0;
  double length_mm = 0.0;
};

class Accumulator {
 public:
  void add(double path_mm, double dev_mm, double dev_rad, int line) {
    const double um = dev_mm * 1e3, urad = dev_rad * 1e6;
    d_.profile.add(path_mm, um, urad, line);
    if (um > d_.max_um || d_.samples == 0) {
      d_.max_um = std::max(d_.max_um, um);
      d_.worst_line = line;
    }
    if (urad > d_.max_urad || d_.samples == 0) {
      d_.max_urad = std::max(d_.max_urad, urad);
      d_.worst_angle_line = line;
    }
    sum_um2_ += um * um;
    sum_urad2_ += urad * urad;
    ++d_.samples;
  }
  FiveAxisDeviation result() const {
    FiveAxisDeviation d = d_;
    if (d.samples) {
      d.rms_um = std::sqrt(sum_um2_ / static_cast<double>(d.samples));
      d.rms_urad = std::sqrt(sum_urad2_ / static_cast<double>(d.samples));
    }
    return d;
  }

 private:
  FiveAxisDeviation d_;
  double sum_um2_ = 0, sum_urad2_ = 0;
};

class Verifier {
 public:
  Verifier(const Machine& machine, const ErrorSet& errors, const FiveAxisVerifyOptions& o)
      : o_(o),
        actual_tools_(machine, o.tool_offsets_mm,
                      [&errors, &o](const Machine& m) {
                        return std::make_unique<FiveAxisTransform>(m, errors, o.outside);
                      }),
        nominal_tools_(machine, o.tool_offsets_mm,
                       [&o](const Machine& m) {
                         return std::make_unique<FiveAxisTransform>(m, ErrorSet{}, o.outside);
                       }),
        tf_(&actual_tools_.get(-1)),
        nominal_tf_(&nominal_tools_.get(-1)) {}

  // A tool change in `file` at `line` (the post's rule: without a tool
  // table, a second tool after moves is refused). `moved`: moves before it.
  void use_tool(int tool, bool moved, const std::string& file, int line) {
    try {
      tf_ = &actual_tools_.change_to(tool, moved);
      nominal_tf_ = &nominal_tools_.change_to(tool, moved);
    } catch (const std::invalid_argument& e) {
      throw InputError(file, line, e.what());
    }
  }

  // Nominal tool axis of move k at parameter s.
  Vector3d axis_at(const FiveAxisMove& m, double s) const {
    if (!m.by_angles) return slerp_axis(m.a0, m.a1, s);
    const AxisVector q = m.q0 + s * (m.q1 - m.q0);
    return nominal_tf_->nominal(q).axis;
  }

  // Smallest angle between `axis` and the nominal tool axis along the move
  // (17 samples, then golden-section refinement around the best).
  double min_angle(const FiveAxisMove& m, const Vector3d& axis) const {
    auto f = [&](double s) { return angle_between(axis, axis_at(m, s)); };
    int best = 0;
    double best_v = f(0.0);
    for (int i = 1; i <= 16; ++i) {
      const double v = f(i / 16.0);
      if (v < best_v) {
        best_v = v;
        best = i;
      }
    }
    double lo = std::max(0, best - 1) / 16.0, hi = std::min(16, best + 1) / 16.0;
    const GoldenSectionResult r = golden_section(lo, hi, 30, f);
    return std::min({best_v, r.f1, r.f2});
  }

  // Deviation of actual pose a from nominal move n: (mm, rad).
  std::pair<double, double> deviation(const NominalMove& n, const ToolPose& a) const {
    return {nc::distance_to_path(n.m.tip, a.tip_mm), min_angle(n.m, a.axis)};
  }

  int samples_for(double tip_mm, double rot_rad) const {
    const int a = static_cast<int>(std::ceil(tip_mm / o_.sample_step_mm));
    const int b = static_cast<int>(std::ceil(rot_rad * units::kDegPerRad / 0.5));
    return std::max({8, a, b});
  }

  // The deviation of actual pose a from the nominal moves around *cursor:
  // the distance to the nearest move of the window and the smallest axis
  // angle among the moves about as near (within twice that plus 5 um: moves
  // that meet or retrace each other) and the cursor's move and its
  // neighbours. The cursor moves to the first move from the cursor on that
  // is within 0.1 mm of the nearest: where a path crosses or retraces
  // itself, an uncompensated sample tens of um off its own move can be
  // nearer to a later one, which must not pull the cursor ahead. Returns
  // (mm, rad).
  std::pair<double, double> deviation_near_cursor(const std::vector<NominalMove>& moves,
                                                  const ToolPose& a, size_t& cursor) const {
    const size_t lo = cursor >= 2 ? cursor - 2 : 0, hi = std::min(moves.size(), cursor + kWindow);
    double best = 1e300;
    std::array<double, kWindow + 2> dist{};
    for (size_t k = lo; k < hi; ++k) {
      dist[k - lo] = nc::distance_to_path(moves[k].m.tip, a.tip_mm);
      best = std::min(best, dist[k - lo]);
    }
    size_t best_k = hi;
    for (size_t k = cursor; k < hi && best_k == hi; ++k)
      if (dist[k - lo] <= best + 0.1) best_k = k;
    if (best_k == hi) best_k = cursor;
    double best_ang = 1e300;
    for (size_t k = lo; k < hi; ++k) {
      const bool near_cursor = k + 1 >= best_k && k <= best_k + 1;
      if (near_cursor || dist[k - lo] <= 2 * best + 0.005)
        best_ang = std::min(best_ang, min_angle(moves[k].m, a.axis));
    }
    cursor = best_k;
    return {best, best_ang};
  }

  const FiveAxisVerifyOptions& o_;
  ToolTransforms actual_tools_, nominal_tools_;
  const FiveAxisTransform* tf_;          ///< the tool in the spindle's, with the errors
  const FiveAxisTransform* nominal_tf_;  ///< and without
};

// Before: the nominal program under ideal TCP interpolation; its feed moves
// into *moves.
FiveAxisDeviation nominal_deviation(Verifier& v, std::istream& nominal,
                                    const std::string& nominal_name, const Machine& machine,
                                    const FiveAxisVerifyOptions& options,
                                    std::vector<NominalMove>& moves) {
  const Machine& mach = v.tf_->machine();
  FiveAxisReader reader(nominal, nominal_name, machine, options.form, options.initial);
  Accumulator acc;
  double path_mm = 0.0;  // tip travel of the feed moves so far
  AxisVector prev = mach.home;
  if (options.initial.q.size() == mach.axis_count())
    for (int k = 0; k < mach.axis_count(); ++k)
      if (is_rotary(mach.axis_order[static_cast<size_t>(k)])) prev[k] = options.initial.q[k];
  FiveAxisLine l;
  bool moved = false;
  while (reader.next(l)) {
    if (l.tool >= 0) v.use_tool(l.tool, moved, nominal_name, l.line);
    if (!l.has_move) continue;
    if (v.o_.progress) v.o_.progress(nominal_name, static_cast<std::size_t>(l.line), 0);
    moved = true;
    const FiveAxisMove& m = l.move;
    auto nominal_u = [&](double s) {
      const Vector3d p = nc::point_on(m.tip, s);
      if (m.by_angles) return v.nominal_tf_->axes_for_angles(m.q0 + s * (m.q1 - m.q0), p);
      ToolPose pose{p, slerp_axis(m.a0, m.a1, s)};
      return v.nominal_tf_->axes_for_pose(pose, prev);
    };
    try {
      if (m.rapid) {
        prev = nominal_u(1.0);
        continue;
      }
      NominalMove n{m, l.line, nc::path_length_mm(m.tip)};
      const double rot =
          m.by_angles ? (m.q1 - m.q0).lpNorm<Eigen::Infinity>() : angle_between(m.a0, m.a1);
      const int count = v.samples_for(n.length_mm, rot);
      for (int i = 1; i <= count; ++i) {
        const AxisVector u = nominal_u(static_cast<double>(i) / count);
        prev = u;
        const ToolPose a = v.tf_->actual(u);
        const auto [d, ang] = v.deviation(n, a);
        acc.add(path_mm + n.length_mm * i / count, d, ang, l.line);
      }
      path_mm += n.length_mm;
      moves.push_back(n);
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw_if_unexpected(e, nominal_name, l.line);  // a bug is said to be one
      throw InputError(nominal_name, l.line, e.what());
    }
  }
  return acc.result();
}

// After: the compensated program's axes, interpolated linearly, against the
// nominal feed moves.
FiveAxisDeviation compensated_deviation(Verifier& v, std::istream& compensated,
                                        const std::string& compensated_name, const Machine& machine,
                                        const std::vector<NominalMove>& moves) {
  const Machine& mach = v.tf_->machine();
  FiveAxisReader reader(compensated, compensated_name, machine, InputForm::kMachineAxes,
                        InitialPose{});
  Accumulator acc;
  double path_mm = 0.0;
  AxisVector u_prev = mach.home;
  bool known = false;
  size_t cursor = 0;
  FiveAxisLine l;
  bool moved = false;
  while (reader.next(l)) {
    if (l.tool >= 0) v.use_tool(l.tool, moved, compensated_name, l.line);
    if (!l.has_move) continue;
    if (v.o_.progress) v.o_.progress(compensated_name, static_cast<std::size_t>(l.line), 0);
    moved = true;
    const FiveAxisMove& m = l.move;
    AxisVector u1 = m.q1;
    for (int k = 0, lin = 0; k < mach.axis_count(); ++k)
      if (!is_rotary(mach.axis_order[static_cast<size_t>(k)])) u1[k] = m.tip.end_mm[lin++];
    if (m.rapid || !known || moves.empty()) {
      u_prev = u1;
      known = true;
      continue;
    }
    try {
      const ToolPose p0 = v.tf_->actual(u_prev), p1 = v.tf_->actual(u1);
      double rot = 0;
      for (int k = 0; k < mach.axis_count(); ++k)
        if (is_rotary(mach.axis_order[static_cast<size_t>(k)]))
          rot = std::max(rot, std::abs(u1[k] - u_prev[k]));
      const double chord_mm = (p1.tip_mm - p0.tip_mm).norm();
      const int count = v.samples_for(chord_mm, rot);
      for (int i = 1; i <= count; ++i) {
        const AxisVector u = u_prev + (static_cast<double>(i) / count) * (u1 - u_prev);
        const ToolPose a = v.tf_->actual(u);
        // Nearest nominal feed move around the cursor.
        const auto [best, best_ang] = v.deviation_near_cursor(moves, a, cursor);
        acc.add(path_mm + chord_mm * i / count, best, best_ang, l.line);
      }
      path_mm += chord_mm;
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw_if_unexpected(e, compensated_name, l.line);  // a bug is said to be one
      throw InputError(compensated_name, l.line, e.what());
    }
    u_prev = u1;
  }
  return acc.result();
}

}  // namespace

FiveAxisVerifyResult verify_five_axis(std::istream& nominal, const std::string& nominal_name,
                                      std::istream& compensated,
                                      const std::string& compensated_name, const Machine& machine,
                                      const ErrorSet& errors,
                                      const FiveAxisVerifyOptions& options) {
  Verifier v(machine, errors, options);
  FiveAxisVerifyResult r;
  std::vector<NominalMove> moves;
  r.before = nominal_deviation(v, nominal, nominal_name, machine, options, moves);
  r.after = compensated_deviation(v, compensated, compensated_name, machine, moves);
  return r;
}

}  // namespace volmap::post
