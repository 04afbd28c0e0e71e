// The fixture of the export tests: the small three-axis sample model and the
// table every golden file is made from, and reading what an export wrote.
#pragma once

#include <array>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "maps/exports/exporters.h"
#include "maps/tables/table_builder.h"
#include "tests/support/test_paths.h"

namespace volmap::maps::test_exports {

namespace fs = std::filesystem;

inline const ErrorModel& small_model() {
  static const ErrorModel model(
      load_machine_json(test::source_path("tests/data/maps/small-3axis.json")),
      load_errors_csv(test::source_path("tests/data/maps/small-3axis.csv")));
  return model;
}

// The table every golden file is made from: 50 mm spacing, 5 x 3 x 3 nodes,
// two X direction layers; provenance fixed so the files do not depend on
// the checkout's path.
inline const VolumetricTable& small_table() {
  static const VolumetricTable t = [] {
    VolumetricTable t = build_table(small_model(), {50, 50, 50});
    t.errors_source = "tests/data/maps/small-3axis.csv";
    return t;
  }();
  return t;
}

inline std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Every export gets the errors file too (csv, json and the Siemens and
// LinuxCNC formats ignore it; isg-csv and heidenhain's KinematicsComp
// tables need it).
inline ExportOptions with_errors() {
  ExportOptions o;
  o.errors = &small_model().errors();
  return o;
}

inline const ExportFile& file_named(const std::vector<ExportFile>& files, const std::string& name) {
  for (const ExportFile& f : files)
    if (f.name == name) return f;
  throw std::runtime_error("no file " + name);
}

// The errors file's own value of a component of X in one direction (mm).
inline double x_error(Component c, double x, int dir) {
  const AxisErrors& e = *small_model().errors().errors_of(AxisName::X);
  std::array<double, kComponentCount> v;
  evaluate_table(dir > 0 ? e.plus : e.minus, x, OutsidePolicy::kError, v);
  return v[static_cast<size_t>(c)];
}

}  // namespace volmap::maps::test_exports
