// The libraries name fields in their messages (`tolerance_um`); the command
// line shows the flags (--tolerance-um): cli/message_wording.h. Every field
// a library message names is an option of a volmap command, so no message
// ever tells a user to type a flag that does not exist.
#include "cli/message_wording.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <string>

#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace volmap::cli {
namespace {

struct Apps {
  CLI::App app{"volmap"};
  CLI::App* post = app.add_subcommand("post");
  CLI::App* verify = app.add_subcommand("verify");
  double tolerance = 0;
  bool clamp = false;
  Apps() {
    post->add_option("--tolerance-um", tolerance);
    post->add_flag("--clamp", clamp);
    verify->add_flag("--clamp", clamp);
  }
};

TEST(MessageWording, FieldsOfTheRunningCommandBecomeItsFlags) {
  Apps a;
  EXPECT_EQ(flag_wording("raise `tolerance_um` or check the arc", a.app, a.post),
            "raise --tolerance-um or check the arc");
  EXPECT_EQ(flag_wording("`clamp` and `clamp`", a.app, a.verify), "--clamp and --clamp");
}

TEST(MessageWording, FieldsOfAnotherCommandNameIt) {
  Apps a;
  EXPECT_EQ(flag_wording("(`verify.clamp` holds the end values)", a.app, a.post),
            "(volmap verify --clamp holds the end values)");
}

TEST(MessageWording, WhatNamesNoOptionStaysAsWritten) {
  Apps a;
  for (const char* kept : {"raise `tolerance_um`",                // verify has no --tolerance-um
                           "the errors of `volmap sensitivity`",  // not a field: a space
                           "`Clamp`", "`clamp.`", "`verify.clamp.x`", "a ` alone", "`", "``",
                           "`post.nothing`", "ends with `clamp"}) {
    EXPECT_EQ(flag_wording(kept, a.app, a.verify), kept) << kept;
  }
  EXPECT_EQ(flag_wording("`clamp`", a.app, nullptr), "`clamp`");
}

// The option names of every volmap command, from its --help.
std::map<std::string, std::set<std::string>> command_options() {
  std::map<std::string, std::set<std::string>> options;
  const std::regex flag(R"(--[a-z][a-z0-9-]*)");
  const test::CliResult top = test::run_volmap("--help");
  const std::regex command(R"(\n  ([a-z]+) {2,})");
  for (std::sregex_iterator c(top.out.begin(), top.out.end(), command), end; c != end; ++c) {
    const std::string name = (*c)[1];
    const std::string help = test::run_volmap(name + " --help").out;
    for (std::sregex_iterator f(help.begin(), help.end(), flag); f != end; ++f)
      options[name].insert(f->str());
  }
  return options;
}

TEST(MessageWording, EveryFieldALibraryMessageNamesIsAnOption) {
  const auto options = command_options();
  ASSERT_GE(options.size(), 9u);
  // Backquoted fields inside string literals (a line with a quote that is
  // not a comment line) of the libraries' sources.
  const std::regex field(R"(`([a-z][a-z0-9_]*)(\.([a-z][a-z0-9_]*))?`)");
  int fields = 0;
  for (const char* library : {"core", "gcode", "maps", "postproc"}) {
    for (const auto& entry :
         std::filesystem::recursive_directory_iterator(test::source_path(library))) {
      const std::string ext = entry.path().extension();
      if (ext != ".cc" && ext != ".h") continue;
      std::ifstream in(entry.path());
      int line_number = 0;
      for (std::string line; std::getline(in, line);) {
        ++line_number;
        const size_t text = line.find_first_not_of(' ');
        if (text == std::string::npos || line.compare(text, 2, "//") == 0) continue;
        if (line.find('"') == std::string::npos) continue;
        for (std::sregex_iterator m(line.begin(), line.end(), field), end; m != end; ++m) {
          ++fields;
          const bool qualified = (*m)[2].matched;
          std::string flag = "--" + std::string((*m)[qualified ? 3 : 1]);
          std::replace(flag.begin(), flag.end(), '_', '-');
          bool found = false;
          for (const auto& [command, flags] : options)
            found = found || ((!qualified || command == (*m)[1]) && flags.count(flag));
          EXPECT_TRUE(found) << entry.path().string() << ":" << line_number << ": " << m->str()
                             << " names no option of a volmap command";
        }
      }
    }
  }
  EXPECT_GE(fields, 40);  // the messages of tests/bad and of the exports at least
}

}  // namespace
}  // namespace volmap::cli
