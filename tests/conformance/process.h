// Running a program as a subprocess for the conformance engine: argv (no
// shell), a working folder, extra environment, standard input from
// /dev/null, standard output and error to files, and a wall-clock limit.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace volmap::conformance {

struct ProcessResult {
  int exit_code = -1;  ///< the exit status, or -1 when it did not exit normally
  int signal = 0;      ///< the signal that ended it (0: none)
  bool timed_out = false;
  std::string out, err;  ///< what it wrote (read back from the files)
};

struct ProcessSpec {
  std::vector<std::string> argv;
  std::string cwd;                                       ///< "" : the current folder
  std::vector<std::pair<std::string, std::string>> env;  ///< added to the environment
  std::string out_file, err_file;                        ///< where stdout and stderr go
  double timeout_s = 60.0;
};

/// Runs it and waits (killing it at the timeout). Throws std::runtime_error
/// when it cannot be started.
ProcessResult run_process(const ProcessSpec& spec);

/// The bytes of a file ("" when it cannot be read).
std::string read_file(const std::string& path);
/// Writes the bytes (creating or truncating the file); throws on failure.
void write_file(const std::string& path, const std::string& bytes);

}  // namespace volmap::conformance
