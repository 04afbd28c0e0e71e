// The volmap export command (docs/exports.md): a table made with volmap map,
// then exported, writes the files the library makes.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/model/errors_csv.h"
#include "core/model/errors_import.h"
#include "core/model/machine_json.h"
#include "maps/exports/exporters.h"
#include "maps/tables/table_builder.h"
#include "maps/tables/table_file.h"
#include "tests/maps/export_fixture.h"
#include "tests/support/test_paths.h"

namespace volmap::maps {
namespace {

namespace fs = std::filesystem;

using namespace test_exports;  // the fixture of export_fixture.h

// ---- the command ----

struct RunResult {
  int status;
  std::string out;
};
RunResult run(const std::string& args) {
  const std::string cmd = test::volmap_binary() + " " + args + " 2>&1";
  RunResult r{};
  FILE* p = popen(cmd.c_str(), "r");
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int st = pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

TEST(ExportCommand, MapThenExportWritesTheFiles) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("export_cmd_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string table = (dir / "t.vmt").string();
  const std::string machine = test::source_path("tests/data/maps/small-3axis.json");
  const std::string errors = test::source_path("tests/data/maps/small-3axis.csv");
  RunResult r = run("map --machine " + machine + " --errors " + errors + " --spacing 50,50,50 -o " +
                    table + " --json");
  ASSERT_EQ(r.status, 0) << r.out;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["nodes"], 45);
  EXPECT_EQ(doc["layers"].size(), 2u);
  r = run("export --table " + table + " --format linuxcnc -o " + (dir / "lcnc").string());
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_TRUE(fs::exists(dir / "lcnc" / "X.comp"));
  // The exported files equal the library's export of the same table.
  const VolumetricTable t = load_table(table);
  EXPECT_EQ(read_file(dir / "lcnc" / "Y.comp"),
            file_named(export_table(t, "linuxcnc"), "Y.comp").text);
  // Errors: one line, exit 1, nothing written. isg-csv needs the component
  // errors: the file the table names, gone here, or --errors.
  const fs::path gone = dir / "gone.csv";
  fs::copy_file(errors, gone);
  const std::string table_gone = (dir / "gone.vmt").string();
  ASSERT_EQ(run("map --machine " + machine + " --errors " + gone.string() +
                " --spacing 50,50,50 -o " + table_gone)
                .status,
            0);
  fs::remove(gone);
  r = run("export --table " + table_gone + " --format isg-csv -o " + (dir / "isg").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  EXPECT_FALSE(fs::exists(dir / "isg"));
  r = run("export --table " + table + " --format isg-csv --errors " + errors + " -o " +
          (dir / "isg").string());
  ASSERT_EQ(r.status, 0) << r.out;
  // The exported ISG CSV is itself an error source for map (detected).
  r = run("map --machine " + machine + " --errors " + (dir / "isg" / "isg_errors.csv").string() +
          " --spacing 50,50,50 -o " + (dir / "t2.vmt").string());
  ASSERT_EQ(r.status, 0) << r.out;
  r = run("export --table " + table + " --format fanuc --detection-unit-um 0.1 -o " +
          (dir / "fanuc").string());
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_TRUE(fs::exists(dir / "fanuc" / "fanuc_pitch.txt"));
  EXPECT_TRUE(fs::exists(dir / "fanuc" / "fanuc_3d_transcription.csv"));  // 30i by default
  // The FANUC options reach the tape: the series' record form, the merged 3605.
  r = run("export --table " + table +
          " --format fanuc --fanuc-series 0i-D --fanuc-param-3605 01000000 "
          "--fanuc-reference-direction - -o " +
          (dir / "fanuc16").string());
  ASSERT_EQ(r.status, 0) << r.out;
  const std::string tape = read_file(dir / "fanuc16" / "fanuc_pitch.txt");
  EXPECT_NE(tape.find("\nN03605A1P01000001A2P01000000A3P01000000\n"), std::string::npos) << tape;
  EXPECT_FALSE(fs::exists(dir / "fanuc16" / "fanuc_3d_transcription.csv"));
  EXPECT_NE(read_file(dir / "fanuc16" / "FANUC.txt").find("1006#5 ZMI = 1"), std::string::npos);
  r = run("export --table " + table + " --format fanuc --fanuc-series 0i -o " +
          (dir / "fanuc0i").string());
  EXPECT_EQ(r.status, 2) << r.out;  // a usage error
  EXPECT_NE(r.out.find("0i-D and 0i-F differ"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "fanuc0i"));
  r = run("export --table " + table + " --format csv -o " + table);
  EXPECT_EQ(r.status, 1) << r.out;
  r = run("map --machine " + machine + " --errors " + errors + " --spacing 50,50,50 -o " + errors);
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.out.find("input"), std::string::npos) << r.out;
  std::ofstream(dir / "bad.vmt") << "VOLMAPTB garbage";
  r = run("export --table " + (dir / "bad.vmt").string() + " --format csv -o " +
          (dir / "x").string());
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.out.find("bad.vmt"), std::string::npos) << r.out;
  r = run("map --machine " + machine + " --errors " + errors + " --spacing 50,50 -o " + table);
  EXPECT_EQ(r.status, 2);  // a usage error
  // -o - writes an export of one file to standard output, and refuses more.
  r = run("export --table " + table + " --format siemens-lec -o -");
  ASSERT_EQ(r.status, 0) << r.out;
  EXPECT_EQ(r.out.rfind("%_N_AX_EEC_INI\n", 0), 0u) << r.out;
  EXPECT_FALSE(fs::exists("-"));
  r = run("export --table " + table + " --format linuxcnc -o -");
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_NE(r.out.find("writes 4 files (X.comp, Y.comp, Z.comp, linuxcnc-joints.ini)"),
            std::string::npos)
      << r.out;
  r = run("export --table " + table + " --format nosuch -o " + (dir / "n").string());
  EXPECT_EQ(r.status, 2) << r.out;
  EXPECT_FALSE(fs::exists(dir / "n"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace volmap::maps
