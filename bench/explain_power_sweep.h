// The sweep of the detection-power benchmark (bench/explain_power.h): every
// effect on every design that can reveal it, at multiples of its detectable
// amplitude and at each noise level, plus null recordings of every design;
// the table and the goals of issue #20.
#pragma once

#include <array>
#include <functional>
#include <set>

#include "bench/explain_power.h"

namespace volmap::power {

struct SweepOptions {
  std::vector<double> noises_um = {0.3, 1.0};
  std::vector<double> multiples = {0.5, 1.0, 1.5, 2.0};  ///< of the detectable amplitude
  int seeds = 25;             ///< recordings per effect, design, noise and multiple
  int nulls_per_design = 15;  ///< null recordings per design and noise
  int threads = 0;            ///< 0: every core
};

/// The form CI runs: one noise level, 1.5 times the detectable amplitude.
inline SweepOptions reduced_options() {
  SweepOptions o;
  o.noises_um = {1.0};
  o.multiples = {1.5};
  o.seeds = 5;
  o.nulls_per_design = 23;
  return o;
}

struct Tally {
  int n = 0, detected = 0, same_form = 0, within = 0, others = 0;
};

struct CellResult {
  std::string effect, design;
  double noise_um = 0;
  std::optional<double> detectable;  ///< a_min in the effect's unit; none: not revealed
  std::string unit;
  std::vector<Tally> by_multiple;
};

struct SweepResult {
  std::vector<CellResult> cells;
  std::map<std::string, Tally> nulls;  ///< by design: n, and "others" = recordings with a finding
  std::size_t recordings = 0;
  std::vector<double> multiples;
};

inline SweepResult sweep(const SweepOptions& opt,
                         const std::function<void(std::int64_t, std::int64_t)>& progress = {}) {
  const std::vector<Design> ds = designs();
  const std::vector<EffectOnDesigns> es = effects();
  const Runner runner;
  SweepResult res;
  res.multiples = opt.multiples;
  // The cells, and each one's detectable amplitude from a null recording of
  // its design (seed 1, kept out of the tallies).
  struct CellJob {
    Cell cell;
    std::size_t result;
  };
  std::vector<CellJob> cells;
  for (const EffectOnDesigns& e : es)
    for (int di : e.designs)
      for (double noise : opt.noises_um) {
        cells.push_back({{&ds[static_cast<std::size_t>(di)], &e.effect, noise}, res.cells.size()});
        CellResult cr;
        cr.effect = e.effect.name;
        cr.design = ds[static_cast<std::size_t>(di)].name;
        cr.noise_um = noise;
        cr.by_multiple.resize(opt.multiples.size());
        res.cells.push_back(cr);
      }
  parallel_for(static_cast<std::int64_t>(cells.size()), thread_count(opt.threads),
               [&](std::int64_t i, int) {
                 const CellJob& j = cells[static_cast<std::size_t>(i)];
                 res.cells[j.result].detectable = runner.run(j.cell, 0.0, 1).detectable;
               });
  // Every recording: (cell or null design, multiple, seed).
  struct Job {
    std::size_t cell = 0;  ///< into cells; SIZE_MAX: a null of `design`
    std::size_t multiple = 0;
    const Design* design = nullptr;
    double noise = 0;
    int seed = 0;
  };
  std::vector<Job> jobs;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (!res.cells[c].detectable) continue;
    for (std::size_t m = 0; m < opt.multiples.size(); ++m)
      for (int s = 0; s < opt.seeds; ++s)
        jobs.push_back({c, m, nullptr, 0, 1000 + 100 * static_cast<int>(m) + s});
  }
  for (const Design& d : ds)
    for (double noise : opt.noises_um)
      for (int s = 0; s < opt.nulls_per_design; ++s)
        jobs.push_back({SIZE_MAX, 0, &d, noise, 5000 + s});
  std::vector<Outcome> outcomes(jobs.size());
  parallel_for(
      static_cast<std::int64_t>(jobs.size()), thread_count(opt.threads),
      [&](std::int64_t i, int) {
        const Job& j = jobs[static_cast<std::size_t>(i)];
        if (j.cell == SIZE_MAX) {
          outcomes[static_cast<std::size_t>(i)] =
              runner.run({j.design, nullptr, j.noise}, 0, j.seed);
        } else {
          const double a = opt.multiples[j.multiple] * *res.cells[j.cell].detectable;
          outcomes[static_cast<std::size_t>(i)] = runner.run(cells[j.cell].cell, a, j.seed);
        }
      },
      progress);
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const Job& j = jobs[i];
    const Outcome& o = outcomes[i];
    if (j.cell == SIZE_MAX) {
      Tally& t = res.nulls[fmt::format("{}, noise {} um", j.design->name, j.noise)];
      ++t.n;
      t.others += o.other_findings > 0;
      continue;
    }
    Tally& t = res.cells[j.cell].by_multiple[j.multiple];
    ++t.n;
    t.detected += o.detected;
    t.same_form += o.detected && o.same_form;
    t.within += o.detected && o.within_3se;
    t.others += o.other_findings > 0;
  }
  res.recordings = jobs.size() + cells.size();
  return res;
}

inline std::string percent(int k, int n) {
  return n ? fmt::format("{:.0f} %", 100.0 * k / n) : std::string("–");
}

/// The markdown table of docs/explain.md.
inline std::string table(const SweepResult& r, const SweepOptions& opt) {
  std::string s = "| effect | design | noise σ (µm) | detectable a_min |";
  for (double m : r.multiples) s += fmt::format(" detected at {} a_min |", m);
  s += " in the injected form | within 3 SE | recordings with another finding "
       "|\n|---|---|---|---|---|";
  for (std::size_t i = 0; i < r.multiples.size(); ++i) s += "---|";
  s += "---|---|\n";
  for (const CellResult& c : r.cells) {
    s += fmt::format("| {} | {} | {} | {} |", c.effect, c.design, c.noise_um,
                     c.detectable ? fmt::format("{:.3g}", *c.detectable) : "not revealed");
    Tally all;
    for (const Tally& t : c.by_multiple) {
      s += fmt::format(" {} |", percent(t.detected, t.n));
      all.detected += t.detected;
      all.same_form += t.same_form;
      all.within += t.within;
      all.others += t.others;
      all.n += t.n;
    }
    s += fmt::format(" {} | {} | {} |\n", percent(all.same_form, all.detected),
                     percent(all.within, all.same_form), percent(all.others, all.n));
  }
  int nulls = 0, with_finding = 0;
  s += "\n| null design | recordings | with any finding |\n|---|---|---|\n";
  for (const auto& [design, t] : r.nulls) {
    s += fmt::format("| {} | {} | {} |\n", design, t.n, t.others);
    nulls += t.n;
    with_finding += t.others;
  }
  s += fmt::format("| all | {} | {} ({}) |\n", nulls, with_finding,
                   nulls ? fmt::format("{:.2f} %", 100.0 * with_finding / nulls) : "–");
  (void)opt;
  return s;
}

/// The goals of issue #20; empty when all are met: at 1.5 a_min every
/// effect detected in >= 95 % of its recordings (over its designs and
/// noise levels), <= 1 % of null recordings with any finding, the
/// parameter within 3 standard errors in >= 95 % of the detections that
/// report it (a settling drift near the limit may be reported in the
/// steady-rate form, which has no amplitude to compare).
inline std::string missed_goals(const SweepResult& r) {
  std::string missed;
  std::size_t at15 = r.multiples.size();
  for (std::size_t i = 0; i < r.multiples.size(); ++i)
    if (std::abs(r.multiples[i] - 1.5) < 1e-9) at15 = i;
  std::map<std::string, Tally> by_effect;
  Tally detections;
  for (const CellResult& c : r.cells) {
    if (!c.detectable) continue;
    for (const Tally& t : c.by_multiple) {
      detections.detected += t.detected;
      detections.same_form += t.same_form;
      detections.within += t.within;
    }
    if (at15 == r.multiples.size()) continue;
    Tally& e = by_effect[c.effect];
    e.n += c.by_multiple[at15].n;
    e.detected += c.by_multiple[at15].detected;
  }
  for (const auto& [effect, t] : by_effect)
    if (t.detected < 0.95 * t.n)
      missed += fmt::format("  {}: detected in {} of {} recordings at 1.5 a_min (goal 95 %)\n",
                            effect, t.detected, t.n);
  int nulls = 0, with_finding = 0;
  for (const auto& [design, t] : r.nulls) {
    nulls += t.n;
    with_finding += t.others;
  }
  if (with_finding > 0.01 * nulls)
    missed += fmt::format("  {} of {} null recordings with a finding (goal <= 1 %)\n", with_finding,
                          nulls);
  if (detections.within < 0.95 * detections.same_form)
    missed += fmt::format(
        "  parameters within 3 SE in {} of {} detections in the injected form (goal 95 %)\n",
        detections.within, detections.same_form);
  return missed;
}

}  // namespace volmap::power
