// The bad-input catalogue (issue 8; shared/spec/cli.md conventions): one
// file per rule of the specs (errors.md, recordings.md,
// docs/machine-format.md, the NC reader of docs/post.md, simulation plans,
// tool tables and parameter files) and per unsupported NC construct, each
// run through the
// CLI. For every file: exit status 1, one line on stderr that is the golden
// message tests/bad/<kind>/<name>.expected (UPDATE_GOLDEN=1 regenerates) and
// names the file and the line (or JSON path), nothing written (the output
// folder stays empty: no output, no temporary), the input unmodified.
//
// Inputs: tests/bad/<kind>/<name>.<ext>; the errors and recordings readers'
// own catalogues (tests/data/errors/bad, tests/data/recordings/bad, checked
// word by word by errors_csv_test and recordings_test) are reused, their
// goldens kept here.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/support/cli_in_source.h"

namespace volmap::test {
namespace {

namespace fs = std::filesystem;

struct Kind {
  const char* name;                     ///< folder under tests/bad
  std::vector<const char*> input_dirs;  ///< relative to the repository
  const char* ext;
  const char* args;  ///< {IN} and {OUT} are replaced
};

const char* kPostArgs =
    "post --machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv "
    "--work-offset 250,200,100";

const std::vector<Kind>& kinds() {
  static const std::vector<Kind> k = {
      {"nc",
       {"tests/bad/nc"},
       ".ngc",
       "post --machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv "
       "--work-offset 250,200,100 --tool-table tests/bad/tool.tbl {IN} -o {OUT}"},
      {"machine",
       {"tests/bad/machine"},
       ".json",
       "map --machine {IN} --errors samples/errors/hsu-3axis.csv --spacing 100,100,100 -o {OUT}"},
      {"errors",
       {"tests/data/errors/bad", "tests/bad/errors"},
       ".csv",
       "map --machine samples/machines/hsu-3axis.json --errors {IN} --spacing 100,100,100 -o "
       "{OUT}"},
      {"recordings",
       {"tests/data/recordings/bad", "tests/bad/recordings"},
       ".csv",
       "identify --machine samples/machines/hsu-3axis.json --recordings {IN} -o {OUT}"},
      {"plan",
       {"tests/bad/plan"},
       ".json",
       "simulate --machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv "
       "--plan {IN} -o {OUT}"},
      {"tooltable", {"tests/bad/tooltable"}, ".tbl", nullptr},
      {"varfile", {"tests/bad/varfile"}, ".var", nullptr},
  };
  return k;
}

std::string args_for(const Kind& k, const std::string& in, const std::string& out) {
  std::string a;
  if (std::string(k.name) == "tooltable")
    a = std::string(kPostArgs) + " --tool-table {IN} samples/programs/pocket.ngc -o {OUT}";
  else if (std::string(k.name) == "varfile")
    a = "post --machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv "
        "--var-file {IN} samples/programs/pocket.ngc -o {OUT}";
  else
    a = k.args;
  for (const auto& [key, value] :
       {std::pair<std::string, std::string>{"{IN}", in}, {"{OUT}", out}}) {
    const size_t at = a.find(key);
    a.replace(at, key.size(), value);
  }
  return a;
}

struct Case {
  const Kind* kind;
  std::string input;  ///< relative to the repository
  std::string stem;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  for (const Kind& k : kinds())
    for (const char* dir : k.input_dirs) {
      const fs::path d = fs::path(source_path(dir));
      if (!fs::is_directory(d)) continue;
      for (const fs::directory_entry& e : fs::directory_iterator(d))
        if (e.path().extension() == k.ext)
          out.push_back({&k, std::string(dir) + "/" + e.path().filename().string(),
                         e.path().stem().string()});
    }
  std::sort(out.begin(), out.end(), [](const Case& a, const Case& b) {
    return std::string(a.kind->name) + "/" + a.stem < std::string(b.kind->name) + "/" + b.stem;
  });
  return out;
}

std::string case_name(const testing::TestParamInfo<Case>& info) {
  std::string n = std::string(info.param.kind->name) + "_" + info.param.stem;
  for (char& c : n)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return n;
}

class BadInput : public testing::TestWithParam<Case> {};

TEST_P(BadInput, RefusedWithTheGoldenMessageAndNothingWritten) {
  const Case& c = GetParam();
  const fs::path out_dir = fresh_dir(std::string("bad_") + c.kind->name + "_" + c.stem);
  const fs::path out = out_dir / "out";
  const std::string before = file_bytes(source_path(c.input));
  ASSERT_FALSE(before.empty() && c.stem != "empty") << c.input;

  const CliResult r = run_volmap_in_source(args_for(*c.kind, c.input, out.string()));

  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_TRUE(fs::is_empty(out_dir)) << "something was written in " << out_dir;
  EXPECT_EQ(file_bytes(source_path(c.input)), before) << c.input << " was modified";
  // One line, "volmap: FILE:LINE[:COLUMN]: ..." or "volmap: FILE:/json/path: ...".
  ASSERT_FALSE(r.err.empty());
  EXPECT_EQ(r.err.back(), '\n');
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  const std::string prefix = "volmap: " + c.input + ":";
  ASSERT_EQ(r.err.rfind(prefix, 0), 0u) << "does not name " << c.input << ": " << r.err;
  const char next = r.err.size() > prefix.size() ? r.err[prefix.size()] : '\0';
  if (next == '/') {
    SUCCEED();  // a JSON path
  } else {
    const int line = std::atoi(r.err.c_str() + prefix.size());
    EXPECT_GT(line, 0) << "no line number: " << r.err;
  }

  const fs::path golden =
      fs::path(source_path("tests/bad")) / c.kind->name / (c.stem + ".expected");
  if (update_golden()) {
    std::ofstream(golden, std::ios::binary) << r.err;
  } else {
    EXPECT_EQ(r.err, file_bytes(golden)) << "golden " << golden << " (UPDATE_GOLDEN=1 regenerates)";
  }
  fs::remove_all(out_dir);
}

INSTANTIATE_TEST_SUITE_P(Catalogue, BadInput, testing::ValuesIn(cases()), case_name);

// Every golden belongs to an input: a renamed or removed input leaves none behind.
TEST(BadInputCatalogue, EveryGoldenHasAnInput) {
  std::vector<std::string> inputs;
  for (const Case& c : cases()) inputs.push_back(std::string(c.kind->name) + "/" + c.stem);
  for (const fs::directory_entry& e : fs::recursive_directory_iterator(source_path("tests/bad")))
    if (e.path().extension() == ".expected") {
      const std::string key =
          e.path().parent_path().filename().string() + "/" + e.path().stem().string();
      EXPECT_NE(std::find(inputs.begin(), inputs.end(), key), inputs.end())
          << e.path() << " has no input";
    }
  EXPECT_GE(inputs.size(), 100u);
}

// "-" reads standard input: a bad program there is named <stdin>, with its
// line, and nothing reaches standard output or the output file.
TEST(BadInputCatalogue, StandardInputIsNamedInMessages) {
  const fs::path d = fresh_dir("bad_stdin");
  const std::string post =
      "post --machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv "
      "--work-offset 250,200,100 - ";
  const CliResult to_file = run_volmap_in_source(post + "-o " + (d / "out.ngc").string() +
                                                 " < tests/bad/nc/cutter_comp_g41.ngc");
  EXPECT_EQ(to_file.status, 1);
  // (Without a tool table G41 D1 has no diameter.)
  EXPECT_EQ(to_file.err.rfind("volmap: <stdin>:4:5: G41/G42 uses tool 1, whose diameter", 0), 0u)
      << to_file.err;
  EXPECT_TRUE(fs::is_empty(d));
  const CliResult to_stdout =
      run_volmap_in_source(post + "-o - < tests/bad/nc/parameter_undefined.ngc");
  EXPECT_EQ(to_stdout.status, 1);
  EXPECT_EQ(to_stdout.err.rfind("volmap: <stdin>:4:5: named parameter #<depth>", 0), 0u)
      << to_stdout.err;
  // Standard output too gets nothing, even when the failure comes after
  // lines that were already post-processed (they are spooled, not streamed).
  EXPECT_TRUE(to_stdout.out.empty()) << to_stdout.out;
  const std::string late_program = (d / "late.ngc").string();
  std::ofstream(late_program) << "G21 G90\nG0 X10 Y10 Z10\nG1 X20 F100\nG1 X30\nG41 X40\n";
  const CliResult late = run_volmap_in_source(
      "post --machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv "
      "--work-offset 250,200,100 " +
      late_program + " -o -");
  EXPECT_EQ(late.status, 1);
  EXPECT_NE(late.err.find("late.ngc:5:"), std::string::npos) << late.err;
  EXPECT_TRUE(late.out.empty()) << late.out;
  fs::remove(late_program);
  const CliResult errors = run_volmap_in_source(
      "map --machine samples/machines/hsu-3axis.json --errors - --spacing 100,100,100 -o " +
      (d / "t.vmt").string() + " < tests/data/errors/bad/nan_cell.csv");
  EXPECT_EQ(errors.status, 1);
  EXPECT_NE(errors.err.find(":3:"), std::string::npos) << errors.err;
  EXPECT_TRUE(fs::is_empty(d));
  fs::remove_all(d);
}

// An input that does not exist: exit 1, one line naming it, nothing written.
TEST(BadInputCatalogue, MissingInputsAreNamed) {
  const fs::path d = fresh_dir("bad_missing");
  const std::string out = (d / "out").string();
  for (const std::string& a :
       {"post --machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv "
        "--work-offset 250,200,100 nonexistent.ngc -o " +
            out,
        "post --machine nonexistent.json --errors samples/errors/hsu-3axis.csv "
        "samples/programs/pocket.ngc -o " +
            out,
        "post --machine samples/machines/hsu-3axis.json --errors nonexistent.csv "
        "samples/programs/pocket.ngc -o " +
            out,
        "post --machine samples/machines/hsu-3axis.json --errors samples/errors/hsu-3axis.csv "
        "--tool-table nonexistent.tbl samples/programs/pocket.ngc -o " +
            out,
        "identify --machine samples/machines/hsu-3axis.json --recordings nonexistent.csv -o " + out,
        "export --table nonexistent.vmt --format csv -o " + out}) {
    const CliResult r = run_volmap_in_source(a);
    EXPECT_EQ(r.status, 1) << a;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find("nonexistent"), std::string::npos) << r.err;
    EXPECT_TRUE(fs::is_empty(d)) << a;
  }
  fs::remove_all(d);
}

// -o onto an input is refused (same path, another spelling of it, a
// symbolic link to it) and the input is untouched; nothing else is written.
TEST(BadInputCatalogue, OutputOntoAnInputIsRefused) {
  const fs::path d = fresh_dir("onto_input");
  for (const char* f : {"samples/machines/hsu-3axis.json", "samples/errors/hsu-3axis.csv",
                        "samples/programs/pocket.ngc", "tests/data/recordings/spec_laser.csv",
                        "samples/plans/laser-x.json"})
    fs::copy_file(source_path(f), d / fs::path(f).filename());
  fs::create_symlink(d / "pocket.ngc", d / "link.ngc");
  const std::string m = (d / "hsu-3axis.json").string(), e = (d / "hsu-3axis.csv").string(),
                    p = (d / "pocket.ngc").string(), rec = (d / "spec_laser.csv").string(),
                    plan = (d / "laser-x.json").string();
  const std::string dots = (d / "." / "pocket.ngc").string();
  const std::string post = "post --machine " + m + " --errors " + e + " --work-offset 250,200,100 ";
  struct Onto {
    std::string args, input;
  };
  const std::vector<Onto> cases = {
      {post + p + " -o " + p, p},
      {post + p + " -o " + dots, p},
      {post + p + " -o " + (d / "link.ngc").string(), p},
      {post + p + " -o " + m, m},
      {post + p + " -o " + e, e},
      {"map --machine " + m + " --errors " + e + " --spacing 100,100,100 -o " + e, e},
      {"map --machine " + m + " --errors " + e + " --spacing 100,100,100 -o " + m, m},
      {"identify --machine " + m + " --recordings " + rec + " -o " + rec, rec},
      {"simulate --machine " + m + " --errors " + e + " --plan " + plan + " -o " + plan, plan},
      {"simulate --machine " + m + " --errors " + e + " --plan " + plan + " -o " + e, e},
  };
  std::vector<std::pair<fs::path, std::string>> before;
  for (const fs::directory_entry& f : fs::directory_iterator(d))
    before.emplace_back(f.path(), file_bytes(f.path()));
  for (const Onto& c : cases) {
    const CliResult r = run_volmap_in_source(c.args);
    EXPECT_NE(r.status, 0) << c.args;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find("input"), std::string::npos) << c.args << ": " << r.err;
    size_t files = 0;
    for (const fs::directory_entry& f : fs::directory_iterator(d)) {
      ++files;
      (void)f;
    }
    EXPECT_EQ(files, before.size()) << "a file was left behind by " << c.args;
    for (const auto& [path, bytes] : before)
      EXPECT_EQ(file_bytes(path), bytes) << path << " changed by " << c.args;
  }
  fs::remove_all(d);
}

}  // namespace
}  // namespace volmap::test
