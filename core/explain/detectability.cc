// Each candidate's test and detectable amplitude (findings.h, detection.h).
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/explain/detection.h"
#include "core/explain/findings.h"

namespace volmap::explanation {
namespace {

/// The nonlinear parameter a candidate's detectable size is quoted at.
std::optional<std::pair<std::string, double>> quoted_at(const Candidate& c, double theta) {
  if (c.grid.empty()) return std::nullopt;
  if (c.effect == "cyclic") return std::pair<std::string, double>{"period_mm", theta};
  if (c.effect == "thermal_drift") return std::pair<std::string, double>{"tau_s", theta};
  if (c.effect == "reversal") return std::pair<std::string, double>{"length_mm", theta};
  return std::pair<std::string, double>{"order", theta};
}

/// Noncentrality per squared unit of amplitude, for the least visible
/// amplitude of the candidate, from the projected Gram matrix in physical
/// coefficient units; 0 when the design cannot reveal it.
double visibility(const Candidate& c, const Eigen::MatrixXd& S_phys, const Eigen::VectorXd& floor) {
  const Eigen::Index k = S_phys.rows();
  switch (c.amplitude) {
    case Candidate::Amplitude::kPair: {
      if (k < 2) return 0;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(S_phys.topLeftCorner<2, 2>());
      const double lo = eig.eigenvalues()[0];
      return lo > std::min(floor[0], floor[1]) ? lo : 0.0;
    }
    case Candidate::Amplitude::kEachColumn: {
      double lo = std::numeric_limits<double>::infinity();
      for (Eigen::Index j = 0; j < k; ++j)
        lo = std::min(lo, S_phys(j, j) > floor[j] ? S_phys(j, j) : 0.0);
      return std::isfinite(lo) ? lo : 0.0;
    }
    case Candidate::Amplitude::kFirst:
      break;
  }
  return k > 0 && S_phys(0, 0) > floor[0] ? S_phys(0, 0) : 0.0;
}

}  // namespace

std::vector<CandidateResult> candidate_results(const CandidateContext& ctx, const Selection& sel) {
  const Observations& obs = ctx.obs;
  const LinearModel& final_model = sel.model;
  const double n = static_cast<double>(obs.count);
  const double dof = std::max(1.0, n - static_cast<double>(final_model.k()));
  const double sigma2 = final_model.rss / dof;
  std::vector<CandidateResult> out;
  for (const CandidateTest& t : sel.tests) {
    const Candidate& c = *t.cand;
    CandidateResult r;
    r.effect = c.effect;
    r.axis = c.axis;
    r.variant = c.variant;
    r.detectable_unit = c.amplitude_unit;
    if (!t.estimable) {  // never tested: no statistic, nothing detectable
      r.status = "not estimable";
      out.push_back(std::move(r));
      continue;
    }
    r.chi2 = t.chi2;
    r.p_value = t.p_value;
    r.critical_chi2 = critical_chi2(t.design);
    const auto asked = ctx.options.detectable_at.find(c.key());
    const double theta = asked != ctx.options.detectable_at.end() ? asked->second : t.theta;
    r.at = quoted_at(c, theta);
    const auto chosen = std::find_if(sel.chosen.begin(), sel.chosen.end(),
                                     [&](const SelectedEffect& s) { return s.fitted.cand == &c; });
    if (chosen != sel.chosen.end())
      r.status = chosen->confounded ? "confounded" : "finding";
    else
      r.status = t.p_value < kFamilyAlpha ? "not taken" : "not significant";
    // The model it is tested against: the final one, without the candidate
    // when it is in it.
    LinearModel reference = final_model;
    if (chosen != sel.chosen.end()) {
      reference = without_block(final_model, chosen->first_col, chosen->fitted.block.cols.cols(),
                                c.nonlinear);
      fit(obs, reference);
    }
    const ColumnBlock b = make_column_block(obs, c.build(theta), c.per_run);
    // physical coefficient = normalised * scale: S_phys = D^-1 S D^-1
    const Eigen::VectorXd inv = b.scale.cwiseInverse();
    const Eigen::MatrixXd S_phys =
        inv.asDiagonal() * projected_gram(reference, b) * inv.asDiagonal();
    // a direction keeping less than 1e-6 of its column is spanned already
    const Eigen::VectorXd floor = 1e-6 * n * inv.cwiseProduct(inv);
    const double per_unit = visibility(c, S_phys, floor);
    TestDesign d = t.design;
    d.family = sel.first_family;
    d.residual_dof = dof;
    if (per_unit > 0) r.detectable = std::sqrt(detectable_noncentrality(d) * sigma2 / per_unit);
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace volmap::explanation
