// Forward selection with the backward check (selection.h).
#include "core/explain/selection.h"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>

#include "core/explain/confounding.h"

namespace volmap::explanation {
namespace {

constexpr double kMinDeltaBic = -10.0;  ///< confounded: BIC within this margin of the best
constexpr double kAbsorbed = 1e-3;      ///< residual share of a column the model spans
constexpr double kConfoundCorrelation = 0.98;
constexpr double kConfoundGainShare = 0.9;

// One finding per effect and axis; geometric errors missing from a fixed
// baseline are one per error name (EA0Z and EB0Z are both squareness of Z).
std::string used_key(const Candidate& c) {
  std::string k = c.effect + "/" + (c.axis ? axis_letter(*c.axis) : "-");
  if (c.effect == "squareness" || c.effect == "straightness" || c.effect == "angular" ||
      (c.effect == "scale" && c.variant.size() > 2) ||
      (c.effect == "reversal" && !c.variant.empty()))
    k += "/" + c.variant;
  return k;
}

/// Candidates not tried on this recording.
bool left_out(const Candidate& c, const ExplainOptions& opt,
              const std::set<std::string>& design_blocked) {
  // Without the machine the rotary axes' lines are a guess: effects of
  // a rotary axis (its wobble, its positioning, a sag driven by its
  // angle) would be fitted to the guess's levers and named with
  // confidence they do not have. Left out; notes says so.
  if (opt.machine_assumed &&
      ((c.axis && is_rotary(*c.axis)) || c.effect == "rotary_wobble" ||
       c.effect == "rotary_positioning" ||
       (c.effect == "sag" && (c.variant == "A" || c.variant == "B" || c.variant == "C"))))
    return true;
  if (c.effect == "thermal_drift" && c.axis && design_blocked.count(axis_letter(*c.axis)))
    return true;
  return c.effect == "scale" && c.axis && design_blocked.count(axis_letter(*c.axis));
}

class Selector {
 public:
  Selector(const CandidateContext& ctx, const std::vector<Candidate>& cands,
           const std::set<std::string>& design_blocked, std::vector<Confounded>& confounded)
      : obs_(ctx.obs),
        options_(ctx.options),
        cands_(cands),
        design_blocked_(design_blocked),
        confounded_(confounded) {}

  Selection run(LinearModel baseline, std::optional<double> baseline_heldout_rms_um) {
    sel_.model = std::move(baseline);
    sel_.heldout_rms_um = baseline_heldout_rms_um;
    for (int step = 0; step < options_.max_findings + 4; ++step) {
      std::vector<FittedCandidate> fits = fit_remaining();
      std::sort(fits.begin(), fits.end(), [](const FittedCandidate& a, const FittedCandidate& b) {
        return a.bic != b.bic ? a.bic < b.bic : a.cand->key() < b.cand->key();
      });
      if (!take_best(fits)) break;
      if (static_cast<int>(std::count_if(sel_.chosen.begin(), sel_.chosen.end(),
                                         [](const SelectedEffect& s) { return !s.confounded; })) >=
          options_.max_findings)
        break;
    }
    backward_check();
    for (const Candidate& c : cands_) {
      const auto t = tests_.find(&c);
      if (t != tests_.end()) sel_.tests.push_back(t->second);
    }
    return std::move(sel_);
  }

 private:
  /// Every candidate not taken yet, fitted given the current model.
  std::vector<FittedCandidate> fit_remaining() {
    std::vector<FittedCandidate> fits;
    const std::string stage =
        fmt::format("testing the candidates for finding {}", sel_.chosen.size() + 1);
    for (std::size_t i = 0; i < cands_.size(); ++i) {
      const Candidate& c = cands_[i];
      if (options_.progress) options_.progress(stage, i, cands_.size());
      if (used_.count(used_key(c))) continue;
      if (left_out(c, options_, design_blocked_)) continue;
      const auto h = hints_.find(c.key());
      std::optional<FittedCandidate> f = fit_candidate(
          obs_, sel_.model, c, h == hints_.end() ? std::nullopt : std::optional<double>(h->second));
      if (f && c.refine) hints_[c.key()] = f->theta;
      if (!f) continue;
      if (f->gain.absorbed_share < kAbsorbed) {
        CandidateTest& t = tests_[&c];
        t.cand = &c;
        t.estimable = false;
        continue;
      }
      fits.push_back(std::move(*f));
    }
    const double family = static_cast<double>(std::max<std::size_t>(1, fits.size()));
    if (sel_.chosen.empty()) sel_.first_family = family;
    for (const FittedCandidate& f : fits) {
      CandidateTest& t = tests_[f.cand];
      t.cand = f.cand;
      t.estimable = true;
      t.theta = f.theta;
      t.design = design_of(f);
      t.design.family = family;
      t.chi2 = statistic(sel_.model.rss, f.gain.rss, t.design);
      t.p_value = corrected_p_value(t.chi2, t.design);
    }
    return fits;
  }

  /// How candidate f is tested: its projected rank and look-elsewhere
  /// (cached from the first step it was tried, against that step's model),
  /// the residual degrees of freedom of the model with it.
  TestDesign design_of(const FittedCandidate& f) {
    const Candidate& c = *f.cand;
    auto it = designs_.find(&c);
    if (it == designs_.end()) it = designs_.emplace(&c, scan_design(c, f.theta)).first;
    TestDesign d = it->second;
    d.residual_dof = std::max(
        1.0, static_cast<double>(obs_.count) - static_cast<double>(sel_.model.k()) - d.columns);
    return d;
  }

  TestDesign scan_design(const Candidate& c, double theta) const {
    TestDesign d;
    auto basis = [&](double th) {
      const ColumnBlock b = make_column_block(obs_, c.build(th), c.per_run);
      // unit-RMS columns: squared norm n; below 1e-6 of it a direction is spanned
      return orthonormal_basis(projected_out(sel_.model, b.cols),
                               1e-6 * static_cast<double>(obs_.count));
    };
    {  // the rank of the projected columns, from their Gram matrix
      const Eigen::MatrixXd S =
          projected_gram(sel_.model, make_column_block(obs_, c.build(theta), c.per_run));
      const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(S).eigenvalues();
      const Eigen::Index rank =
          (ev.array() > 1e-6 * static_cast<double>(obs_.count)).cast<Eigen::Index>().sum();
      d.columns = static_cast<double>(std::max<Eigen::Index>(1, rank));
    }
    if (c.grid.empty()) return d;
    if (!c.refine) {
      d.discrete = static_cast<double>(c.grid.size());
      return d;
    }
    if (c.path_length) {
      d.path_length = c.path_length();
      return d;
    }
    auto between = [&](std::size_t i, double frac) {
      const double a = c.grid[i], b = c.grid[i + 1];
      if (c.log_refine) return std::exp((1 - frac) * std::log(a) + frac * std::log(b));
      if (c.effect == "cyclic") return 1.0 / ((1 - frac) / a + frac / b);  // even in frequency
      return (1 - frac) * a + frac * b;
    };
    d.path_length = path_length(
        static_cast<int>(c.grid.size()),
        [&](int i) { return basis(c.grid[static_cast<std::size_t>(i)]); },
        [&](int i, double frac) { return basis(between(static_cast<std::size_t>(i), frac)); });
    return d;
  }

  /// chi2 = (RSS0 - RSS1) / sigma^2, sigma^2 from the model with the candidate.
  static double statistic(double rss_without, double rss_with, const TestDesign& d) {
    const double sigma2 = std::max(rss_with, 1e-300) / std::max(1.0, d.residual_dof);
    return std::max(0.0, rss_without - rss_with) / sigma2;
  }

  /// Takes the best candidate (by BIC) that passes the detection test and
  /// holds up on held-out runs; false when none does.
  bool take_best(std::vector<FittedCandidate>& fits) {
    const LinearModel& model = sel_.model;
    const double bic_now = bic(obs_, model.rss, static_cast<int>(model.k()) + model.nonlinear);
    for (FittedCandidate& f : fits) {
      if (!(tests_[f.cand].p_value < kFamilyAlpha)) continue;  // noise could do this
      LinearModel next = with_block(model, f.block, f.cand->nonlinear);
      fit(obs_, next);
      const std::optional<double> ho = heldout_rms(obs_, next);
      if (ho && sel_.heldout_rms_um && !(*ho < *sel_.heldout_rms_um)) continue;  // does not hold up
      SelectedEffect s;
      s.delta_bic = f.bic - bic_now;
      s.rms_before_um = rms_of(obs_, model.rss);
      s.rms_after_um = rms_of(obs_, next.rss);
      s.heldout_before_um = sel_.heldout_rms_um;
      s.heldout_after_um = ho;
      s.first_col = model.k();
      s.confounded = find_confounded(f, fits, s.relative_to, s.relative_is_sum);
      used_.insert(used_key(*f.cand));
      tests_[f.cand].taken = true;
      s.fitted = std::move(f);
      sel_.chosen.push_back(std::move(s));
      sel_.model = std::move(next);
      sel_.heldout_rms_um = ho;
      return true;
    }
    return false;
  }

  /// Confounding: another candidate explains the same structure almost as
  /// well. Reports the pair and takes the other out of the search.
  bool find_confounded(FittedCandidate& f, const std::vector<FittedCandidate>& fits,
                       std::optional<AxisName>& relative_to, bool& relative_is_sum) {
    const LinearModel& model = sel_.model;
    const double gain_best = model.rss - f.gain.rss;
    for (const FittedCandidate& g : fits) {
      if (&g == &f) continue;
      if (g.cand->effect == f.cand->effect && g.cand->axis == f.cand->axis) continue;
      // Nearly as good by the same measure (BIC within the selection margin)
      // and the same structure (fitted deviations correlated).
      if (model.rss - g.gain.rss < kConfoundGainShare * gain_best) continue;
      const bool bic_close = g.bic - f.bic <= -kMinDeltaBic;
      const bool sizes_differ = g.block.cols.cols() != f.block.cols.cols();
      if (!bic_close && !sizes_differ) continue;
      if (f.gain.fitted.size() == 0) f.gain = profile(obs_, model, f.block, true);
      const Eigen::VectorXd g_fitted = profile(obs_, model, g.block, true).fitted;
      const double rho = correlation(f.gain.fitted, g_fitted);
      if (std::abs(rho) < kConfoundCorrelation) continue;
      // Nested (a squareness is a sag's linear term): the smaller one is the
      // parsimonious explanation, and the larger one's extra columns get
      // their own test at the next step. Not two readings of one structure,
      // unless the larger one's leading columns alone (a scale error's
      // linear term beside a pitch with its Abbe lever) are as good an
      // account as the smaller: two physics of one size, confounded, whatever
      // BIC charges the larger one for its extra columns.
      if (sizes_differ && nested(f.block, g.block)) {
        if (larger_adds_something(f, g) || !leading_part_explains(f, g)) continue;
      } else if (!bic_close) {
        continue;
      }
      // One effect on two axes with one signature (the lags of X and Y on
      // a circle): not two physics but a difference the design shows, the
      // split between the axes it cannot. A finding relative to the other.
      // Columns of one size, equal or opposite: the data show the sum or the
      // difference of the two coefficients. Of different sizes (a diagonal
      // beam) only a weighted sum: confounded.
      const double along = std::abs(rho) > 0.999 && g.cand->effect == f.cand->effect &&
                                   g.block.cols.cols() == f.block.cols.cols()
                               ? same_size_correlation(f.block, g.block)
                               : 0.0;
      if (std::abs(along) > 0.999) {
        relative_to = g.cand->axis;
        relative_is_sum = along > 0;
        used_.insert(used_key(*g.cand));
        continue;
      }
      add_confounded_once(confounded_, same_structure(obs_, f, g, rho));
      used_.insert(used_key(*g.cand));
      return true;
    }
    return false;
  }

  /// Correlation of two blocks' first columns with the model projected out,
  /// when their physical sizes agree within 1 % (then the data show the sum
  /// or the difference of the coefficients); 0 otherwise.
  double same_size_correlation(const ColumnBlock& a, const ColumnBlock& b) const {
    const Eigen::VectorXd pa = projected_out(sel_.model, a.cols.leftCols(1)).col(0);
    const Eigen::VectorXd pb = projected_out(sel_.model, b.cols.leftCols(1)).col(0);
    const double size_a = pa.norm() / a.scale[0], size_b = pb.norm() / b.scale[0];
    if (!(size_b > 0) || std::abs(size_a / size_b - 1) > 0.01) return 0.0;
    return correlation(pa, pb);
  }

  /// Whether the columns of the smaller block lie in the span of the larger
  /// one's (with the model): each keeps under 1e-6 of its squared norm when
  /// projected. Blocks of as many columns are never nested: with the same
  /// span they are two physics with one signature (reversal and servo lag
  /// at one feed), which is confounding.
  bool nested(const ColumnBlock& a, const ColumnBlock& b) const {
    if (a.cols.cols() == b.cols.cols()) return false;
    const bool a_smaller = a.cols.cols() < b.cols.cols();
    const ColumnBlock& small = a_smaller ? a : b;
    LinearModel with_large = with_block(sel_.model, a_smaller ? b : a, 0);
    fit(obs_, with_large);
    const Eigen::MatrixXd rest = projected_out(with_large, small.cols);
    for (Eigen::Index j = 0; j < rest.cols(); ++j)
      if (rest.col(j).squaredNorm() > 1e-6 * small.cols.col(j).squaredNorm()) return false;
    return true;
  }

  /// Whether the larger of two nested candidates explains significantly more
  /// than the smaller (its extra columns pass the detection test): then it
  /// is the better account (a scale with the curvature of the positioning
  /// error, against a pitch that has only the slope).
  bool larger_adds_something(const FittedCandidate& f, const FittedCandidate& g) const {
    const bool f_larger = f.block.cols.cols() > g.block.cols.cols();
    const FittedCandidate& large = f_larger ? f : g;
    const FittedCandidate& small = f_larger ? g : f;
    TestDesign d;
    d.columns = static_cast<double>(large.block.cols.cols() - small.block.cols.cols());
    d.residual_dof =
        std::max(1.0, static_cast<double>(obs_.count) - static_cast<double>(sel_.model.k()) -
                          static_cast<double>(large.block.cols.cols()));
    return corrected_p_value(statistic(small.gain.rss, large.gain.rss, d), d) < kFamilyAlpha;
  }

  /// Whether the leading columns of the larger of two nested candidates, as
  /// many as the smaller has, explain the smaller's structure (fitted
  /// deviations correlated above kConfoundCorrelation).
  bool leading_part_explains(FittedCandidate& f, const FittedCandidate& g) const {
    const bool f_smaller = f.block.cols.cols() < g.block.cols.cols();
    const ColumnBlock& large = f_smaller ? g.block : f.block;
    const Eigen::Index k = std::min(f.block.cols.cols(), g.block.cols.cols());
    ColumnBlock lead;
    lead.cols = large.cols.leftCols(k);
    lead.scale = large.scale.head(k);
    lead.per_run = large.per_run;
    const Eigen::VectorXd small_fit =
        f_smaller ? f.gain.fitted : profile(obs_, sel_.model, g.block, true).fitted;
    return std::abs(correlation(profile(obs_, sel_.model, lead, true).fitted, small_fit)) >=
           kConfoundCorrelation;
  }

  // Backward check: a finding chosen early can become redundant once later
  // ones explain its structure better (a sag that stood in for two
  // squareness errors not yet found). Each finding must still hold up in
  // the final model, by the same two tests as when it entered: removing it
  // fails the detection test's level, and raises the held-out RMS.
  void backward_check() {
    while (drop_one_that_does_not_hold_up()) {
    }
  }

  bool drop_one_that_does_not_hold_up() {
    LinearModel& model = sel_.model;
    std::vector<SelectedEffect>& chosen = sel_.chosen;
    for (std::size_t i = 0; i < chosen.size(); ++i) {
      SelectedEffect& s = chosen[i];
      if (s.confounded) continue;
      const Eigen::Index kc = s.fitted.block.cols.cols();
      LinearModel reduced = without_block(model, s.first_col, kc, s.fitted.cand->nonlinear);
      fit(obs_, reduced);
      TestDesign d = tests_[s.fitted.cand].design;
      d.residual_dof =
          std::max(1.0, static_cast<double>(obs_.count) - static_cast<double>(model.k()));
      bool holds = corrected_p_value(statistic(reduced.rss, model.rss, d), d) < kFamilyAlpha;
      if (holds && sel_.heldout_rms_um) {
        const std::optional<double> ho_reduced = heldout_rms(obs_, reduced);
        holds = !ho_reduced || *sel_.heldout_rms_um < *ho_reduced;
      }
      if (holds) continue;
      tests_[s.fitted.cand].taken = false;
      for (SelectedEffect& later : chosen)
        if (later.first_col > s.first_col) later.first_col -= kc;
      chosen.erase(chosen.begin() + static_cast<std::ptrdiff_t>(i));
      model = std::move(reduced);
      sel_.heldout_rms_um = heldout_rms(obs_, model);
      return true;
    }
    return false;
  }

  const Observations& obs_;
  const ExplainOptions& options_;
  const std::vector<Candidate>& cands_;
  const std::set<std::string>& design_blocked_;
  std::vector<Confounded>& confounded_;
  Selection sel_;
  std::set<std::string> used_;           ///< effect/axis taken
  std::map<std::string, double> hints_;  ///< nonlinear parameters scanned at an earlier step
  std::map<const Candidate*, CandidateTest> tests_;  ///< the last test of each candidate
  std::map<const Candidate*, TestDesign> designs_;   ///< rank and look-elsewhere, first step
};

}  // namespace

Selection select_effects(const CandidateContext& ctx, const std::vector<Candidate>& cands,
                         LinearModel baseline, std::optional<double> baseline_heldout_rms_um,
                         const std::set<std::string>& design_blocked,
                         std::vector<Confounded>& confounded) {
  return Selector(ctx, cands, design_blocked, confounded)
      .run(std::move(baseline), baseline_heldout_rms_um);
}

}  // namespace volmap::explanation
