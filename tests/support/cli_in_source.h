// Runs the built volmap executable from the repository folder, so paths in
// its messages are the relative paths given (golden messages do not depend
// on where the repository lies). Also: byte-exact file reading and a fresh
// empty folder per test for outputs.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "tests/support/cli_run.h"
#include "tests/support/test_paths.h"

namespace volmap::test {

/// `volmap ARGS` with the repository as working folder; standard input from
/// /dev/null unless `args` redirects it.
inline CliResult run_volmap_in_source(const std::string& args) {
  static int calls = 0;
  const std::string err_file = ::testing::TempDir() + "volmap_src_err_" + std::to_string(getpid()) +
                               "_" + std::to_string(++calls) + ".txt";
  const std::string cmd = "cd '" + source_path("") + "' && '" + volmap_binary() + "' </dev/null " +
                          args + " 2>'" + err_file + "'";
  CliResult r;
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int st = pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  std::ifstream f(err_file, std::ios::binary);
  r.err.assign(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  std::remove(err_file.c_str());
  return r;
}

/// The bytes of a file ("" when it cannot be read).
inline std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

/// An empty folder under the test temporary folder, unique to `name`.
inline std::filesystem::path fresh_dir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::path(::testing::TempDir()) /
                                  ("volmap_" + name + "_" + std::to_string(getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

inline bool update_golden() {
  const char* u = std::getenv("UPDATE_GOLDEN");
  return u != nullptr && std::string(u) == "1";
}

}  // namespace volmap::test
