// Runs the built volmap executable as scripts do: exit status, standard
// output, standard error (one temporary file per call: ctest runs in
// parallel).
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <string>

#include "tests/support/test_paths.h"

namespace volmap::test {

struct CliResult {
  int status = -1;
  std::string out, err;
};

inline CliResult run_volmap(const std::string& args) {
  static int calls = 0;
  const std::string err_file = ::testing::TempDir() + "volmap_cli_err_" + std::to_string(getpid()) +
                               "_" + std::to_string(++calls) + ".txt";
  const std::string cmd = volmap_binary() + " " + args + " 2>" + err_file;
  CliResult r;
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int st = pclose(p);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  if (FILE* f = fopen(err_file.c_str(), "r")) {
    while ((n = fread(buf.data(), 1, buf.size(), f)) > 0) r.err.append(buf.data(), n);
    fclose(f);
  }
  std::remove(err_file.c_str());
  return r;
}

}  // namespace volmap::test
