// The volmap executable as scripts call it: exit status, one-line errors,
// JSON output of `sensitivity` (spec: shared/spec/cli.md).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/support/cli_in_source.h"
#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace {

using Result = volmap::test::CliResult;

Result run(const std::string& args) { return volmap::test::run_volmap(args); }

std::string sample(const std::string& rel) { return volmap::test::source_path("samples/" + rel); }

TEST(Cli, SensitivityJsonHasTheContractKeys) {
  const Result r = run("sensitivity --machine " + sample("machines/hsu-3axis.json") +
                       " --at 250,200,150 --model dependent --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["model"], "dependent");
  EXPECT_EQ(doc["at"]["X"], 250.0);
  EXPECT_EQ(doc["gains"].size(), 21u);
  for (const char* k : {"dx", "dy", "dz", "di", "dj", "dk"})
    EXPECT_TRUE(doc["gains"]["EC0X"].contains(k));
  // ISO 230-1 (the default): the squareness turns X's motion, dP = EC0X x
  // Xm: dy = Xm = 250, dx = 0.
  EXPECT_EQ(doc["convention"], "iso230-1");
  EXPECT_NEAR(doc["gains"]["EC0X"]["dy"].get<double>(), 250.0, 1e-9);
  EXPECT_NEAR(doc["gains"]["EC0X"]["dx"].get<double>(), 0.0, 1e-9);
  // Table I's COX is a link error: dy = Xz + Xm = 0 + 250 for the sample
  // (Xz = 0), dx = -Yz, Yz = -180.
  const Result link = run("sensitivity --machine " + sample("machines/hsu-3axis.json") +
                          " --at 250,200,150 --model dependent --convention link --json");
  ASSERT_EQ(link.status, 0) << link.err;
  const auto l = nlohmann::json::parse(link.out);
  EXPECT_EQ(l["convention"], "link");
  EXPECT_NEAR(l["gains"]["EC0X"]["dy"].get<double>(), 250.0, 1e-9);
  EXPECT_NEAR(l["gains"]["EC0X"]["dx"].get<double>(), 180.0, 1e-9);
}

TEST(Cli, SensitivityFiveAxisDefaultsToIndependent) {
  const Result r = run("sensitivity --machine " + sample("machines/lei-hsu-xyzac.json") +
                       " --at 10,20,30,-45,30 --json");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["model"], "independent");
  EXPECT_NEAR(doc["at"]["A"].get<double>(), -45.0, 1e-12);
  EXPECT_TRUE(doc["gains"].contains("EX0C"));
  EXPECT_TRUE(doc["gains"].contains("EY0A"));
  EXPECT_TRUE(doc["gains"].contains("ECC"));
}

TEST(Cli, HumanTableOnStdout) {
  const Result r =
      run("sensitivity --machine " + sample("machines/hsu-3axis.json") + " --at 0,0,0");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("EB0Z"), std::string::npos);
  EXPECT_NE(r.out.find("Table II"), std::string::npos);
}

TEST(Cli, UsageErrorsExitTwo) {
  EXPECT_EQ(run("").status, 2);
  EXPECT_EQ(run("sensitivity --at 1,2,3").status, 2);
  EXPECT_EQ(run("frobnicate").status, 2);
  EXPECT_EQ(run("sensitivity --machine x --at 1,2,3 --model sideways").status, 2);
}

TEST(Cli, BadInputExitsOneWithOneLine) {
  Result r = run("sensitivity --machine /nonexistent.json --at 1,2,3");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("/nonexistent.json"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;

  // A value the option cannot take is a usage error (cli.md: status 2),
  // still one line that says what is wrong.
  r = run("sensitivity --machine " + sample("machines/hsu-3axis.json") + " --at 1,2");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("expected 3 values (X,Y,Z)"), std::string::npos) << r.err;

  r = run("sensitivity --machine " + sample("machines/hsu-3axis.json") + " --at 900,0,0");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("outside the travel"), std::string::npos) << r.err;
}

TEST(Cli, HelpEndsWithAnExample) {
  const Result r = run("sensitivity --help");
  EXPECT_EQ(r.status, 0);
  EXPECT_NE(r.out.find("Example:"), std::string::npos);
}

// Every verb that writes a file takes `--output` as the long form of `-o`:
// the same bytes either way.
TEST(Cli, OutputIsTheLongFormOfO) {
  const std::string dir = volmap::test::fresh_dir("cli_output").string();
  const std::string args = "post --machine " + sample("machines/hsu-3axis.json") + " --errors " +
                           sample("errors/hsu-3axis.csv") + " --work-offset 250,200,100 " +
                           sample("programs/pocket.ngc");
  ASSERT_EQ(run(args + " -o " + dir + "/short.ngc").status, 0);
  ASSERT_EQ(run(args + " --output " + dir + "/long.ngc").status, 0);
  EXPECT_EQ(volmap::test::file_bytes(dir + "/short.ngc"),
            volmap::test::file_bytes(dir + "/long.ngc"));
  for (const char* verb : {"post", "map", "export", "identify", "simulate"})
    EXPECT_NE(run(std::string(verb) + " --help").out.find("-o,--output"), std::string::npos)
        << verb;
}

// A misspelt command or option is named with the nearest one, exit 2.
TEST(Cli, MisspellingsSuggestTheNearestName) {
  Result r = run("posst --machine m.json");
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err,
            "volmap: 'posst' is not a volmap command; did you mean 'post'? (see volmap --help)\n");
  r = run("post --work-ofset 1,2,3 --machine m.json in.ngc -o out.ngc");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("unknown option --work-ofset of volmap post; did you mean --work-offset?"),
            std::string::npos)
      << r.err;
  // A value out of range in plain words, not 1.79e308 in full.
  r = run("post --machine m.json --errors e.csv --tolerance-um -1 in.ngc -o out.ngc");
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err, "volmap: --tolerance-um: value -1 must be positive (see volmap --help)\n");
  r = run("frobnicate");
  EXPECT_EQ(r.err, "volmap: 'frobnicate' is not a volmap command (see volmap --help)\n");
  // --json is a flag everywhere but in explain, where it names a file: a
  // file after the flag is explained, not merely "not expected".
  r = run("verify --machine m.json --nominal a.ngc --program b.ngc --json v.json");
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err,
            "volmap: --json of volmap verify takes no value, so 'v.json' after it was not "
            "expected: it writes the JSON to standard output (redirect it: > v.json); only "
            "volmap explain's --json names a file (see volmap --help)\n");
  r = run("post --machine m.json --json p.json in.ngc -o out.ngc");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--json of volmap post takes no value, so 'p.json' after it"),
            std::string::npos)
      << r.err;
  // The input after a flag is the input: the stray word is the one named.
  r = run("post --machine m.json --clamp in.ngc -o out.ngc extra.ngc");
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.err.find("--clamp of volmap post takes no value"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("extra.ngc"), std::string::npos) << r.err;
}

}  // namespace

// cli.md writes `volmap export --table T --format FORMAT -o DIR`: formats
// that export the component errors themselves (isg-csv) read them from the
// errors file the table names when --errors is not given, with the same
// result as giving it.
TEST(Cli, ExportReadsTheErrorsFileTheTableNames) {
  const std::string dir = ::testing::TempDir() + "cli_test_export_" + std::to_string(getpid());
  const std::string table = dir + ".vmt";
  ASSERT_EQ(run("map --machine " + sample("machines/hsu-3axis.json") + " --errors " +
                sample("errors/hsu-3axis.csv") + " --spacing 50,50,50 -o " + table)
                .status,
            0);
  const Result implicit = run("export --table " + table + " --format isg-csv -o " + dir + "-a");
  ASSERT_EQ(implicit.status, 0) << implicit.err;
  const Result given = run("export --table " + table + " --format isg-csv --errors " +
                           sample("errors/hsu-3axis.csv") + " -o " + dir + "-b");
  ASSERT_EQ(given.status, 0) << given.err;
  auto slurp = [](const std::string& p) {
    std::string s;
    if (FILE* f = std::fopen(p.c_str(), "rb")) {
      std::array<char, 4096> b;
      size_t n;
      while ((n = std::fread(b.data(), 1, b.size(), f)) > 0) s.append(b.data(), n);
      std::fclose(f);
    }
    return s;
  };
  const std::string a = slurp(dir + "-a/isg_errors.csv"), b = slurp(dir + "-b/isg_errors.csv");
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, b);
}

// A table keeps the errors file's name as `volmap map` was given it. From
// another folder, export finds it beside the table or refuses; it never
// leaves the KinematicsComp tables out.
TEST(Cli, ExportRefusesAnErrorsFileItCannotFind) {
  namespace fs = std::filesystem;
  const fs::path dir = volmap::test::fresh_dir("export_relative");
  const std::string table = (dir / "hsu.vmt").string();
  ASSERT_EQ(
      volmap::test::run_volmap_in_source("map --machine samples/machines/hsu-3axis.json --errors "
                                         "samples/errors/hsu-3axis.csv --spacing 50,50,50 -o " +
                                         table)
          .status,
      0);
  // Run from another folder, where the relative name leads nowhere.
  fs::create_directories(dir / "elsewhere");
  auto export_from_dir = [&](const std::string& out) {
    const std::string err = (dir / "err.txt").string();
    const int st =
        std::system(("cd '" + (dir / "elsewhere").string() + "' && '" +
                     volmap::test::volmap_binary() + "' export --table '" + table +
                     "' --format heidenhain -o '" + (dir / out).string() + "' 2>'" + err + "'")
                        .c_str());
    return Result{WIFEXITED(st) ? WEXITSTATUS(st) : -1, "", volmap::test::file_bytes(err)};
  };
  Result r = export_from_dir("a");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("the table was built from the errors file 'samples/errors/hsu-3axis.csv', "
                       "found neither from the current folder nor beside the table; give it with "
                       "--errors E.csv"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "a"));
  // Beside the table, under the name the table keeps: found.
  fs::create_directories(dir / "samples" / "errors");
  fs::copy_file(sample("errors/hsu-3axis.csv"), dir / "samples" / "errors" / "hsu-3axis.csv");
  r = export_from_dir("b");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "b" / "KC_X.COM"));
}

// Errors whose '# machine:' names another machine are refused by every
// command that takes a machine and errors, naming both; --other-machine-errors
// uses them anyway. The same errors under their own machine's name pass.
TEST(Cli, ErrorsOfAnotherMachineAreRefusedUnlessAskedFor) {
  const std::string other = "tests/bad/errors/machine-other.csv";
  const std::string m = "--machine samples/machines/hsu-3axis.json --errors ";
  for (const std::string& args :
       {"kinematics " + m + other + " --forward 100,100,100",
        "sensitivity " + m + other + " --at 100,100,100",
        "post " + m + other + " --work-offset 250,200,100 samples/programs/pocket.ngc -o -"}) {
    const Result r = volmap::test::run_volmap_in_source(args);
    EXPECT_EQ(r.status, 1) << args;
    EXPECT_EQ(r.err,
              "volmap: " + other +
                  ":2: '# machine:' names \"samples/machines/gantry-3axis.json\", but the machine "
                  "is \"hsu-3axis\" (samples/machines/hsu-3axis.json): errors measured on another "
                  "machine give a wrong correction; give this machine's errors, or "
                  "--other-machine-errors to use them anyway\n")
        << args;
    EXPECT_EQ(volmap::test::run_volmap_in_source(args + " --other-machine-errors").status, 0)
        << args;
  }
  EXPECT_EQ(volmap::test::run_volmap_in_source("kinematics " + m +
                                               "samples/errors/hsu-3axis.csv --forward 100,100,100")
                .status,
            0);
}

// verify shows its progress on stderr when stderr is a terminal (cli.md),
// and says nothing there otherwise. script(1) gives the command a terminal.
TEST(Cli, VerifyShowsProgressOnATerminalOnly) {
  namespace fs = std::filesystem;
  const fs::path dir = volmap::test::fresh_dir("verify_progress");
  const std::string out = (dir / "pocket-M.ngc").string();
  const std::string m = " --machine " + sample("machines/hsu-3axis.json") + " --errors " +
                        sample("errors/hsu-3axis.csv") + " --work-offset 250,200,100 ";
  ASSERT_EQ(run("post" + m + sample("programs/pocket.ngc") + " -o " + out).status, 0);
  const std::string verify =
      "verify" + m + "--nominal " + sample("programs/pocket.ngc") + " --program " + out;
  const Result plain = run(verify);
  ASSERT_EQ(plain.status, 0) << plain.err;
  EXPECT_EQ(plain.err, "");
  const std::string log = (dir / "tty.txt").string();
  const int st = std::system(("script -qec '" + volmap::test::volmap_binary() + " " + verify +
                              "' /dev/null > " + log + " 2>&1")
                                 .c_str());
  ASSERT_EQ(WIFEXITED(st) ? WEXITSTATUS(st) : -1, 0);
  const std::string tty = volmap::test::file_bytes(log);
  EXPECT_NE(tty.find("verify: " + sample("programs/pocket.ngc") + " move 1 of "), std::string::npos)
      << tty;
  EXPECT_NE(tty.find("before (nominal program"), std::string::npos) << tty;
  fs::remove_all(dir);
}

// simulate, identify and explain show their stages on a terminal too, and
// write nothing on stderr otherwise.
TEST(Cli, SimulateIdentifyExplainShowProgressOnATerminalOnly) {
  namespace fs = std::filesystem;
  const fs::path dir = volmap::test::fresh_dir("stage_progress");
  const std::string rec = (dir / "probe.csv").string();
  const std::string machine = " --machine " + sample("machines/lei-hsu-xyzac.json");
  const std::string commands[3] = {
      "simulate" + machine + " --errors " + sample("errors/lei-hsu-xyzac.csv") + " --plan " +
          sample("plans/probe-ball.json") + " -o " + rec,
      "identify" + machine + " --recordings " + rec + " -o " + (dir / "id.csv").string(),
      "explain --machine " + sample("machines/hsu-3axis.json") + " --recordings " +
          sample("recordings/reversal.csv")};
  const std::string shown[3] = {"simulate: simulating 64 targets",
                                "identify: Gauss-Newton iteration (1 of 30)",
                                "explain: testing the candidates for finding 1 (1 of "};
  for (int k = 0; k < 3; ++k) {
    SCOPED_TRACE(commands[k]);
    const Result plain = run(commands[k]);
    ASSERT_EQ(plain.status, 0) << plain.err;
    EXPECT_EQ(plain.err.find(shown[k].substr(0, 10)), std::string::npos) << plain.err;
    const std::string log = (dir / "tty.txt").string();
    const int st = std::system(("script -qec '" + volmap::test::volmap_binary() + " " +
                                commands[k] + "' /dev/null > " + log + " 2>&1")
                                   .c_str());
    ASSERT_EQ(WIFEXITED(st) ? WEXITSTATUS(st) : -1, 0);
    const std::string tty = volmap::test::file_bytes(log);
    EXPECT_NE(tty.find(shown[k]), std::string::npos) << tty;
  }
  fs::remove_all(dir);
}

// identify's options that do not fit the machine are usage errors (status 2).
TEST(Cli, IdentifyOptionsThatDoNotFitTheMachineAreUsageErrors) {
  const std::string base = "identify --machine " + sample("machines/hsu-3axis.json") +
                           " --recordings " + sample("recordings/reversal.csv") + " -o " +
                           (volmap::test::fresh_dir("identify_usage") / "e.csv").string();
  for (const char* extra : {" --params EQ0X", " --component EXX", " --component EXX:x"}) {
    const Result r = run(base + extra);
    EXPECT_EQ(r.status, 2) << extra << ": " << r.err;
    EXPECT_NE(r.err.find("(see volmap identify --help)"), std::string::npos) << r.err;
  }
}
