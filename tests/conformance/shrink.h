// Delta debugging (Zeller's ddmin) over the lines of a failing program and
// of its subroutine files: the smallest program the predicate still fails
// on (1-minimal over lines, within a budget of trials).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "tests/conformance/generator.h"

namespace volmap::conformance {

/// The lines of a text with their line ends (the last may have none).
std::vector<std::string> split_lines(const std::string& text);
std::string join_lines(const std::vector<std::string>& lines);

struct ShrinkResult {
  Program program;
  int trials = 0;
  bool budget_exhausted = false;
};

/// `fails(p)`: whether p still fails the same way. At most `max_trials` calls.
ShrinkResult shrink(const Program& failing, const std::function<bool(const Program&)>& fails,
                    int max_trials);

}  // namespace volmap::conformance
