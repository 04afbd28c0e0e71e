#include "core/measure/identify_columns.h"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <stdexcept>

#include "core/common/units.h"

namespace volmap::identification {
namespace {

// Internal units (mm, rad) per parameter unit (um, urad: the units of the estimates).
constexpr double kMmPerUm = 1e-3;
constexpr double kRadPerUrad = 1e-6;

constexpr int kCurveIntervals = 64;     // knots of a fitted polynomial table
constexpr int kPeriodicIntervals = 72;  // 5 degrees: fitted Fourier table

/// An angular parameter in urad, a translational one in um.
void set_unit(ParameterColumn& c, bool angular) {
  c.p.unit = angular ? "urad" : "um";
  c.unit_scale = angular ? kRadPerUrad : kMmPerUm;
}

/// Adds columns without repeating one (`taken`: the names so far).
class ColumnBuilder {
 public:
  ColumnBuilder(const Machine& m, const GainEvaluator& gains, const ErrorSet& known)
      : m_(m), gains_(gains), known_(known) {}

  void add_location(const std::string& given) {
    const std::vector<std::string>& names = gains_.names();
    const int g = gains_.index_of(given);
    const std::optional<ErrorName> n = parse_error_name(given);
    if (g < 0 || !n || !n->location)
      throw std::invalid_argument(
          fmt::format("{} is not a location error of this machine; choose from "
                      "the location errors of `volmap sensitivity`",
                      given));
    const std::string canonical = names[static_cast<std::size_t>(g)];
    if (known_.location.count(canonical))
      throw std::invalid_argument(
          fmt::format("{} is given in the known errors ({}); fit it or hold it, "
                      "not both",
                      canonical, known_.file));
    if (!taken_.insert(canonical).second) return;
    ParameterColumn c;
    c.p.name = canonical;
    c.p.kind = ParameterKind::kLocation;
    c.gain = g;
    set_unit(c, gains_.angular(g));
    cols_.push_back(c);
  }

  void add_component(const ComponentFit& f) {
    const std::optional<ErrorName> n = parse_error_name(f.name);
    const int g = gains_.index_of(f.name);
    if (!n || n->location || g < 0)
      throw ComponentFitError(
          fmt::format("{}: not a component error of this machine (e.g. EXX, EZX, ECC)", f.name));
    if (f.degree < 1 || f.degree > 8)
      throw ComponentFitError(fmt::format("{}:{}: the degree (order) is 1..8", f.name, f.degree));
    if (known_.errors_of(n->axis))
      throw ComponentFitError(
          fmt::format("{}: the known errors ({}) already tabulate axis "
                      "{}; fit components of axes without known tables",
                      f.name, known_.file, axis_char(n->axis)));
    const int ai = *m_.index_of(n->axis);
    const AxisLimits& L = m_.limits[static_cast<std::size_t>(ai)];
    const bool fourier = is_rotary(n->axis) && L.unlimited;
    const bool ang = is_angular(n->component);
    for (int k = 1; k <= f.degree; ++k)
      for (int s = 0; s < (fourier ? 2 : 1); ++s) {
        ParameterColumn c;
        c.p.kind = ParameterKind::kComponent;
        set_unit(c, ang);
        c.gain = g;
        c.axis = n->axis;
        c.axis_index = ai;
        c.fourier = fourier;
        c.power = k;
        c.sine = s == 1;
        if (!fourier) {
          c.centre = 0.5 * (L.min + L.max);
          c.half_span = 0.5 * (L.max - L.min);
        }
        const std::string canonical = gains_.names()[static_cast<std::size_t>(g)];
        c.p.name = fourier ? fmt::format("{}.{}{}", canonical, c.sine ? 's' : 'c', k)
                           : fmt::format("{}.p{}", canonical, k);
        if (!taken_.insert(c.p.name).second) throw ComponentFitError(f.name + " given twice");
        cols_.push_back(c);
      }
  }

  std::vector<ParameterColumn> take() { return std::move(cols_); }

 private:
  const Machine& m_;
  const GainEvaluator& gains_;
  const ErrorSet& known_;
  std::vector<ParameterColumn> cols_;
  std::set<std::string> taken_;
};

/// The table of one axis's fitted component curves (columns `js` of that
/// axis) at theta: values and slopes at evenly spaced knots.
AxisErrors tabulated_curves(const Machine& m, const std::vector<ParameterColumn>& cols,
                            const std::vector<std::string>& gain_names, const std::vector<int>& js,
                            AxisName axis, const Eigen::VectorXd& theta) {
  const ParameterColumn& c0 = cols[static_cast<std::size_t>(js.front())];
  const AxisLimits& L = m.limits[static_cast<std::size_t>(c0.axis_index)];
  AxisErrors ax;
  ax.axis = axis;
  AxisErrorTable& t = ax.plus;
  t.axis = axis;
  t.source = "identified";
  t.periodic = c0.fourier;
  const int n_int = c0.fourier ? kPeriodicIntervals : kCurveIntervals;
  const double lo = c0.fourier ? 0.0 : L.min, hi = c0.fourier ? 2.0 * std::numbers::pi : L.max;
  for (int k = 0; k <= n_int; ++k) {
    const double q = lo + (hi - lo) * k / n_int;
    t.position.push_back(q);
    std::array<double, kComponentCount> v{}, s{};
    for (int j : js) {
      const ParameterColumn& c = cols[static_cast<std::size_t>(j)];
      const ErrorName n = *parse_error_name(gain_names[static_cast<std::size_t>(c.gain)]);
      const auto comp = static_cast<std::size_t>(n.component);
      ax.present[comp] = true;
      v[comp] += theta[j] * c.unit_scale * curve_basis(c, q);
      s[comp] += theta[j] * c.unit_scale * curve_basis_slope(c, q);
    }
    t.value.push_back(v);
    t.slope.push_back(s);
  }
  prepare_lookup(t);
  return ax;
}

}  // namespace

double curve_basis(const ParameterColumn& c, double q) {
  if (c.fourier) return c.sine ? std::sin(c.power * q) : std::cos(c.power * q);
  const double s = (q - c.centre) / c.half_span;
  double v = s;
  for (int k = 1; k < c.power; ++k) v *= s;
  return v;
}

double curve_basis_slope(const ParameterColumn& c, double q) {
  if (c.fourier) return c.sine ? c.power * std::cos(c.power * q) : -c.power * std::sin(c.power * q);
  const double s = (q - c.centre) / c.half_span;
  double v = 1.0;
  for (int k = 1; k < c.power; ++k) v *= s;
  return c.power * v / c.half_span;
}

std::vector<ParameterColumn> physical_columns(const Machine& m, const GainEvaluator& gains,
                                              const ErrorSet& known, const IdentifyOptions& opt) {
  ColumnBuilder builder(m, gains, known);
  if (opt.parameters.empty()) {
    for (const std::string& n : gains.names()) {
      const ErrorName e = *parse_error_name(n);
      if (e.location && !known.location.count(n)) builder.add_location(n);
    }
  } else {
    for (const std::string& n : opt.parameters) builder.add_location(n);
  }
  for (const ComponentFit& f : opt.components) builder.add_component(f);
  return builder.take();
}

void append_setup_offset_columns(std::vector<ParameterColumn>& cols,
                                 const std::vector<int>& row_runs, const Recordings& rec) {
  const std::set<int> runs(row_runs.begin(), row_runs.end());
  for (int r : runs)
    for (int c = 0; c < 3; ++c) {
      ParameterColumn col;
      col.p.kind = ParameterKind::kSetupOffset;
      col.p.unit = "um";
      col.unit_scale = kMmPerUm;
      col.run = r;
      col.coordinate = c;
      const std::string run_name =
          r < 0 ? std::string("none") : rec.run_names[static_cast<std::size_t>(r)];
      col.p.name = fmt::format("offset_{}.run{}", static_cast<char>('x' + c), run_name);
      cols.push_back(col);
    }
}

Eigen::Vector3d physical_gain_w_um(const ParameterColumn& c, const GainEvaluator& gains,
                                   const AxisVector& u) {
  Eigen::Vector3d g_w = gains.dP(c.gain) * (c.unit_scale * units::kUmPerMm);
  if (c.p.kind == ParameterKind::kComponent) g_w *= curve_basis(c, u[c.axis_index]);
  return g_w;
}

ErrorSet errors_at(const Machine& m, const ErrorSet& known,
                   const std::vector<ParameterColumn>& cols,
                   const std::vector<std::string>& gain_names, const Eigen::VectorXd& theta) {
  ErrorSet e = known;
  std::map<AxisName, std::vector<int>> by_axis;
  for (int j = 0; j < static_cast<int>(cols.size()); ++j) {
    const ParameterColumn& c = cols[static_cast<std::size_t>(j)];
    if (c.p.kind == ParameterKind::kLocation) e.location[c.p.name] = theta[j] * c.unit_scale;
    if (c.p.kind == ParameterKind::kComponent) by_axis[c.axis].push_back(j);
  }
  for (const auto& [axis, js] : by_axis)
    e.axis[static_cast<std::size_t>(axis)] = tabulated_curves(m, cols, gain_names, js, axis, theta);
  return e;
}

}  // namespace volmap::identification
