// The reduced form of the detection-power benchmark (bench/explain_power.h,
// issue #20) that CI runs: every effect on every design that can reveal it,
// at 1.5 times its detectable amplitude, one noise level, 5 recordings
// each; 230 null recordings over the ten designs. The goals are the
// full benchmark's (docs/explain.md, "Detection power"): detection of
// every effect in >= 95 % of its recordings, <= 1 % of null recordings
// with any finding, parameters within 3 standard errors in >= 95 % of the
// detections. The recordings are simulated with fixed seeds, so a miss is
// a change of explain's behaviour, not chance.
#include <gtest/gtest.h>

#include "bench/explain_power_sweep.h"

namespace volmap {
namespace {

TEST(ExplainPower, ReducedSweepMeetsTheGoals) {
  const power::SweepOptions opt = power::reduced_options();
  const power::SweepResult r = power::sweep(opt);
  EXPECT_GE(r.recordings, 300u);
  // every effect has at least one design that reveals it
  std::set<std::string> revealed;
  for (const power::CellResult& c : r.cells)
    if (c.detectable) revealed.insert(c.effect);
  EXPECT_EQ(revealed.size(), power::effects().size());
  EXPECT_EQ(power::missed_goals(r), "") << power::table(r, opt);
  std::printf("%s", power::table(r, opt).c_str());
}

}  // namespace
}  // namespace volmap
