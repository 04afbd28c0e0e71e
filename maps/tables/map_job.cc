#include "maps/tables/map_job.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <utility>

namespace volmap::maps {

UncertaintySources uncertainty_sources(const ErrorSet& errors, double repeatability_um,
                                       double repeatability_urad,
                                       const std::string& covariance_path, const Machine& m,
                                       Formulation f) {
  UncertaintySources s;
  s.repeatability = repeatability_from(errors);
  if (repeatability_um >= 0.0 || repeatability_urad >= 0.0) {
    if (!s.repeatability) s.repeatability.emplace();
    if (repeatability_um >= 0.0) s.repeatability->translational_mm = repeatability_um * 1e-3;
    if (repeatability_urad >= 0.0) s.repeatability->angular_rad = repeatability_urad * 1e-6;
  }
  if (!covariance_path.empty()) {
    std::ifstream in(covariance_path);
    if (!in)
      throw std::invalid_argument(
          fmt::format("{}: cannot open the identify report", covariance_path));
    nlohmann::json report;
    try {
      report = nlohmann::json::parse(in);
    } catch (const nlohmann::json::parse_error& e) {
      throw std::invalid_argument(fmt::format("{}: not JSON ({})", covariance_path, e.what()));
    }
    // The report's parameters are location errors in its convention (ISO
    // 230-1 when it does not say: identify wrote it so since 2026-12-03).
    const std::string convention = report.value("convention", "iso230-1");
    if (parse_location_convention(convention) != errors.convention)
      throw std::invalid_argument(fmt::format(
          "{}: identified in the {} convention, and {} gives its location errors in the {} "
          "convention; identify again with --convention {}, or give the errors file it wrote",
          covariance_path, convention, errors.file, location_convention_name(errors.convention),
          location_convention_name(errors.convention)));
    s.covariance = covariance_from_identify(report, m, f, covariance_path);
    if (!s.repeatability) s.repeatability.emplace();
  }
  return s;
}

double FullTableResult::interpolation_um() const {
  return table.pose_correction() ? checked.max_dv_um : checked.max_um();
}

FullTableResult build_full_table(const ErrorModel& model, const FullTableJob& job) {
  FullTableResult r;
  r.method = job.check.method;
  if (!job.spacing.empty()) {
    r.table = build_table(model, job.spacing, job.build, &r.summary);
    r.checked = check_table(model, r.table, job.check);
    // Five-axis: the tolerance is on dv; du is reported beside.
    r.table.achieved_um = r.interpolation_um();
    r.table.checked_with = job.check.method;
    return r;
  }
  const double tol_urad = job.tolerance_urad_or_default();
  AutoSpacingResult a = build_for_tolerance(model, job.tolerance_um_or_default(), job.check,
                                            job.build, job.build.max_bytes, tol_urad);
  r.tolerance_urad = model.machine().has_rotary_axes() ? tol_urad : 0.0;
  r.grids_tried = a.tables_tried;
  r.table = std::move(a.table);
  r.summary = a.build;
  r.checked = a.check;
  return r;
}

namespace {

double norm3(const double* v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

}  // namespace

TableExtremes table_extremes(const VolumetricTable& table) {
  const std::optional<int> ux = table.channel("ux");
  const std::optional<int> uc = table.channel("u");
  const std::optional<int> ei = table.channel("ei");
  const bool five = table.pose_correction();
  std::vector<int> rotary_du;
  if (five)
    for (const GridAxis& g : table.grid)
      if (is_rotary(g.axis)) rotary_du.push_back(*table.channel(correction_channel_name(g.axis)));
  double max_dv = 0.0, max_du = 0.0, max_u = 0.0, max_dq = 0.0, max_du_rot = 0.0;
  for (int layer = 0; layer < table.layer_count(); ++layer)
    for (std::int64_t n = 0; n < table.node_count(); ++n) {
      const double* v = table.at(layer, n);
      max_dv = std::max(max_dv, norm3(v) * 1e3);
      if (uc) max_u = std::max(max_u, v[*uc] * 1e3);
      if (ei) max_dq = std::max(max_dq, norm3(v + *ei) * 1e6);
      if (!rotary_du.empty()) {
        double r2 = 0.0;
        for (int c : rotary_du) r2 += v[c] * v[c];
        max_du_rot = std::max(max_du_rot, std::sqrt(r2) * 1e6);
      }
      if (ux) max_du = std::max(max_du, norm3(v + *ux) * 1e3);
    }
  TableExtremes e;
  e.max_dv_um = max_dv;
  if (ux) e.max_du_um = max_du;
  if (ei) e.max_dq_urad = max_dq;
  if (five) e.max_du_rotary_urad = max_du_rot;
  if (uc) e.max_u_um = max_u;
  return e;
}

FactorizedTable factorized_table_of(const std::string& machine_path, const ErrorModel& model) {
  nlohmann::ordered_json definition;
  {
    std::ifstream in(machine_path);
    definition = nlohmann::ordered_json::parse(in);
  }
  return make_factorized(definition, model);
}

}  // namespace volmap::maps
