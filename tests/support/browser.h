// Loads a self-contained HTML page (a volmap report) in headless Chromium
// (Debian's `chromium`) and collects what its console said: the reports
// must load with no console messages. Tests skip when Chromium is missing,
// unless VOLMAP_REQUIRE_CHROMIUM=1 (CI), where they fail.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace volmap::test {

inline bool have_chromium() { return std::system("command -v chromium >/dev/null 2>&1") == 0; }

/// True when the test may go on to load pages; otherwise it has skipped or
/// failed (VOLMAP_REQUIRE_CHROMIUM=1) and must return.
inline bool chromium_or_skip() {
  if (have_chromium()) return true;
  const char* req = std::getenv("VOLMAP_REQUIRE_CHROMIUM");
  if (req && std::string(req) == "1") {
    ADD_FAILURE() << "chromium is required (VOLMAP_REQUIRE_CHROMIUM=1) but missing";
    return false;
  }
  return false;
}

inline std::string read_text_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Loads `html_path`; returns the DOM after load and the console lines
/// (empty when the page said nothing).
inline void load_in_chromium(const std::string& html_path, std::string& dom, std::string& console) {
  const std::string dom_file = html_path + ".dom", log_file = html_path + ".log";
  const std::string cmd =
      "timeout 120 chromium --headless --disable-gpu --no-sandbox --enable-logging=stderr --v=0 "
      "--virtual-time-budget=1000 --dump-dom file://" +
      html_path + " >" + dom_file + " 2>" + log_file;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  dom = read_text_file(dom_file);
  std::istringstream log(read_text_file(log_file));
  console.clear();
  for (std::string line; std::getline(log, line);)
    if (line.find(":CONSOLE") != std::string::npos || line.find("Uncaught") != std::string::npos)
      console += line + "\n";
}

/// The console check sees errors: a page that throws must produce a line.
/// Chromium writes its console to the log from another process, and under
/// load (ctest -j2 beside a build) a run can end before the line arrives:
/// the check passes when any of three runs sees it, which a broken check
/// never does, instead of failing on the machine's speed.
inline void expect_console_check_sees_errors(const std::string& scratch_html) {
  {
    std::ofstream o(scratch_html);
    o << "<!DOCTYPE html><html><body><script>undefined_function();</script></body></html>\n";
  }
  std::string dom, console;
  for (int attempt = 0; attempt < 3 && console.empty(); ++attempt)
    load_in_chromium(scratch_html, dom, console);
  EXPECT_FALSE(console.empty()) << "the console check does not see errors";
}

}  // namespace volmap::test
