#include "tests/conformance/shrink.h"

#include <algorithm>

namespace volmap::conformance {

std::vector<std::string> split_lines(const std::string& text) {
  std::vector<std::string> lines;
  size_t at = 0;
  while (at < text.size()) {
    size_t end = text.find('\n', at);
    end = end == std::string::npos ? text.size() : end + 1;
    lines.push_back(text.substr(at, end - at));
    at = end;
  }
  return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += l;
  return s;
}

namespace {

struct Budget {
  const std::function<bool(const Program&)>& fails;
  int left;
  int used = 0;
  bool test(const Program& p) {
    if (left <= 0) return false;
    --left;
    ++used;
    return fails(p);
  }
};

// ddmin over one list of lines; `with(lines)` builds the program to test.
std::vector<std::string> ddmin(
    std::vector<std::string> lines, Budget& budget,
    const std::function<Program(const std::vector<std::string>&)>& with) {
  size_t n = 2;
  while (lines.size() >= 2 && budget.left > 0) {
    const size_t chunk = (lines.size() + n - 1) / n;
    bool reduced = false;
    for (size_t start = 0; start < lines.size() && budget.left > 0; start += chunk) {
      std::vector<std::string> rest(lines.begin(), lines.begin() + static_cast<long>(start));
      rest.insert(rest.end(),
                  lines.begin() + static_cast<long>(std::min(lines.size(), start + chunk)),
                  lines.end());
      if (budget.test(with(rest))) {
        lines = std::move(rest);
        n = std::max<size_t>(n - 1, 2);
        reduced = true;
        break;
      }
    }
    if (reduced) continue;
    if (n >= lines.size()) break;
    n = std::min(lines.size(), 2 * n);
  }
  // One line at a time, to 1-minimality (ddmin ends there when chunks are
  // single lines; this also catches the last chunk sizes).
  for (size_t k = 0; k < lines.size() && budget.left > 0 && lines.size() > 1;) {
    std::vector<std::string> rest = lines;
    rest.erase(rest.begin() + static_cast<long>(k));
    if (budget.test(with(rest)))
      lines = std::move(rest);
    else
      ++k;
  }
  return lines;
}

}  // namespace

ShrinkResult shrink(const Program& failing, const std::function<bool(const Program&)>& fails,
                    int max_trials) {
  Budget budget{fails, max_trials};
  Program p = failing;
  // Subroutine files that are not needed at all.
  for (size_t f = 0; f < p.files.size() && budget.left > 0;) {
    Program q = p;
    q.files.erase(q.files.begin() + static_cast<long>(f));
    if (budget.test(q))
      p = std::move(q);
    else
      ++f;
  }
  const std::vector<std::string> main = ddmin(split_lines(p.main), budget, [&](const auto& lines) {
    Program q = p;
    q.main = join_lines(lines);
    return q;
  });
  p.main = join_lines(main);
  for (size_t f = 0; f < p.files.size(); ++f) {
    const std::vector<std::string> lines =
        ddmin(split_lines(p.files[f].second), budget, [&](const auto& l) {
          Program q = p;
          q.files[f].second = join_lines(l);
          return q;
        });
    p.files[f].second = join_lines(lines);
  }
  ShrinkResult r;
  r.program = std::move(p);
  r.trials = budget.used;
  r.budget_exhausted = budget.left <= 0;
  return r;
}

}  // namespace volmap::conformance
