// Progress of a long job on stderr, only when stderr is a terminal (cli.md:
// "Progress on stderr, only when stderr is a terminal"): one line rewritten
// in place at most ten times a second, cleared when the job ends.
#pragma once

#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cstddef>
#include <iostream>
#include <string>

namespace volmap::cli {

class TerminalProgress {
 public:
  explicit TerminalProgress(std::string verb) : verb_(std::move(verb)), on_(isatty(2) != 0) {}
  ~TerminalProgress() {
    if (shown_) std::cerr << "\r" << std::string(width_, ' ') << "\r" << std::flush;
  }
  TerminalProgress(const TerminalProgress&) = delete;
  TerminalProgress& operator=(const TerminalProgress&) = delete;

  /// `total` 0: done counts lines of a program read as it streams.
  void operator()(const std::string& what, std::size_t done, std::size_t total) {
    if (!on_) return;
    const auto now = std::chrono::steady_clock::now();
    if (shown_ && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    show(total ? fmt::format("{}: {} move {} of {}", verb_, what, done + 1, total)
               : fmt::format("{}: {} line {}", verb_, what, done));
  }

  /// A stage of the job ("reading R.csv", "fitting the baseline"), shown at
  /// once; with a total, "what (done+1 of total)", its first step at once
  /// and the others at most ten times a second.
  void stage(const std::string& what, std::size_t done = 0, std::size_t total = 0) {
    if (!on_) return;
    const auto now = std::chrono::steady_clock::now();
    if (total && what == stage_ && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    stage_ = what;
    show(total ? fmt::format("{}: {} ({} of {})", verb_, what, done + 1, total)
               : fmt::format("{}: {}", verb_, what));
  }

 private:
  void show(const std::string& text) {
    std::cerr << "\r" << text << std::string(width_ > text.size() ? width_ - text.size() : 0, ' ')
              << std::flush;
    width_ = std::max(width_, text.size());
    shown_ = true;
  }

  std::string verb_, stage_;
  bool on_ = false, shown_ = false;
  std::size_t width_ = 0;
  std::chrono::steady_clock::time_point last_;
};

}  // namespace volmap::cli
