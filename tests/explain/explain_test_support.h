// What the explain tests share: the sample machines, running `volmap
// explain` on a sample recording, the truth file of a sample, and the checks
// every single-effect sample makes.
#pragma once

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "core/explain/explain.h"
#include "core/measure/identify.h"
#include "core/measure/recordings.h"
#include "core/measure/simulate.h"
#include "core/model/error_model.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "tests/support/browser.h"
#include "tests/support/cli_run.h"
#include "tests/support/plans.h"
#include "tests/support/samples.h"
#include "tests/support/test_paths.h"

namespace volmap::explain_testing {

using json = nlohmann::json;

inline const std::string kM3 = "samples/machines/hsu-3axis.json";
inline const std::string kM5 = "samples/machines/lei-hsu-xyzac.json";

inline std::string temp_path(const std::string& name) {
  return ::testing::TempDir() + "explain_test_" + name;
}

inline std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs `volmap explain` on a sample recording; returns the JSON result.
inline json run_explain(const std::string& recording, const std::string& machine,
                        const std::string& baseline = "") {
  std::string flat = recording;
  for (char& ch : flat)
    if (ch == '/') ch = '_';
  const std::string out =
      temp_path(flat + "_" + machine.substr(machine.find_last_of('/') + 1) + ".json");
  std::remove(out.c_str());
  std::string args = "explain --recordings " + test::source_path(recording) + " --json " + out;
  if (!machine.empty()) args += " --machine " + test::source_path(machine);
  if (!baseline.empty()) args += " --baseline " + test::source_path(baseline);
  const test::CliResult r = test::run_volmap(args);
  EXPECT_EQ(r.status, 0) << r.err;
  const std::string text = slurp(out);
  EXPECT_FALSE(text.empty()) << args;
  return text.empty() ? json::object() : json::parse(text);
}

inline json truth_of(const std::string& name) {
  const json t =
      json::parse(slurp(test::source_path("samples/recordings/" + name + ".effects.json")));
  return t.at("effects").at(0);
}

/// The finding must name the truth's effect and axis, be the only finding,
/// and improve the RMS and the held-out RMS.
inline const json& expect_single_finding(const json& res, const json& truth) {
  EXPECT_EQ(res.at("format"), "volmap-explain/1");
  const json& f = res.at("findings");
  EXPECT_EQ(f.size(), 1u) << res.dump(1);
  static const json empty = json::object();
  if (f.empty()) return empty;
  const json& top = f.at(0);
  EXPECT_EQ(top.at("effect"), truth.at("effect"));
  EXPECT_EQ(top.at("axis"), truth.at("axis"));
  EXPECT_LT(top.at("rms_after_um").get<double>(), top.at("rms_before_um").get<double>());
  if (!top.at("heldout_rms_before_um").is_null()) {
    EXPECT_LT(top.at("heldout_rms_after_um").get<double>(),
              0.98 * top.at("heldout_rms_before_um").get<double>());
    EXPECT_LT(res.at("final").at("heldout_rms_um").get<double>(),
              res.at("baseline").at("heldout_rms_um").get<double>());
  }
  EXPECT_LT(top.at("evidence").at("delta_bic").get<double>(), -10.0);
  EXPECT_FALSE(top.at("explanation").get<std::string>().empty());
  return top;
}

inline double param(const json& finding, const std::string& key) {
  return finding.at("parameters").at(key).get<double>();
}

/// Angle difference in degrees, wrapped to (-180, 180].
inline double angle_diff(double a, double b) { return std::remainder(a - b, 360.0); }

}  // namespace volmap::explain_testing
