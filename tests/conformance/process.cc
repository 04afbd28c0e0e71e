#include "tests/conformance/process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <thread>

namespace volmap::conformance {

std::string read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

void write_file(const std::string& path, const std::string& bytes) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << bytes;
  if (!f) throw std::runtime_error("cannot write " + path);
}

namespace {

// In the child: redirect, change folder, set the environment, exec.
[[noreturn]] void exec_child(const ProcessSpec& spec, const std::vector<char*>& args) {
  setpgid(0, 0);
  const int in = open("/dev/null", O_RDONLY);
  if (in >= 0) dup2(in, 0);
  const auto redirect = [](const std::string& file, int fd) {
    const int f =
        open(file.empty() ? "/dev/null" : file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (f >= 0) dup2(f, fd);
  };
  redirect(spec.out_file, 1);
  redirect(spec.err_file, 2);
  if (!spec.cwd.empty() && chdir(spec.cwd.c_str()) != 0) _exit(126);
  for (const auto& [k, v] : spec.env) setenv(k.c_str(), v.c_str(), 1);
  execvp(args[0], args.data());
  _exit(127);
}

}  // namespace

ProcessResult run_process(const ProcessSpec& spec) {
  if (spec.argv.empty()) throw std::runtime_error("run_process: no program");
  std::vector<char*> args;
  for (const std::string& a : spec.argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) exec_child(spec, args);
  ProcessResult r;
  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  auto pause = std::chrono::microseconds(200);
  for (;;) {
    const pid_t w = waitpid(pid, &status, WNOHANG);
    if (w == pid) break;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (elapsed > spec.timeout_s) {
      r.timed_out = true;
      kill(-pid, SIGKILL);  // the child's own process group: only what it started
      waitpid(pid, &status, 0);
      break;
    }
    std::this_thread::sleep_for(pause);
    if (pause < std::chrono::milliseconds(5)) pause *= 2;
  }
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  if (!spec.out_file.empty()) r.out = read_file(spec.out_file);
  if (!spec.err_file.empty()) r.err = read_file(spec.err_file);
  return r;
}

}  // namespace volmap::conformance
