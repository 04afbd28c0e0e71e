#include "core/common/csv.h"

#include <algorithm>
#include <charconv>
#include <istream>
#include <sstream>
#include <system_error>
#include <utility>

#include "core/common/input_error.h"

namespace volmap::csv {

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\f' || c == '\v' || c == '\r' || c == '\n';
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool is_blank(std::string_view line) { return trim(line).empty(); }

bool is_comment(std::string_view line) {
  line = trim(line);
  return !line.empty() && line.front() == '#';
}

LineReader::LineReader(std::istream& in, std::string file) : in_(in), file_(std::move(file)) {}

bool LineReader::next(std::string& text) {
  if (!std::getline(in_, text)) {
    if (in_.bad()) throw InputError(file_, number_, "read error; check the file and the device");
    return false;
  }
  ++number_;
  if (number_ == 1 && text.starts_with("\xEF\xBB\xBF")) text.erase(0, 3);
  if (!text.empty() && text.back() == '\r') text.pop_back();
  return true;
}

std::vector<std::string> split_lines(const std::string& text) {
  std::istringstream in(text);
  LineReader reader(in, std::string());
  std::vector<std::string> lines;
  std::string line;
  while (reader.next(line)) lines.push_back(line);
  return lines;
}

void split_cells(std::string_view line, std::vector<Cell>& cells) {
  cells.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    const std::size_t end = comma == std::string_view::npos ? line.size() : comma;
    const std::string_view raw = line.substr(start, end - start);
    std::size_t lead = 0;
    while (lead < raw.size() && is_space(raw[lead])) ++lead;
    cells.push_back({trim(raw), static_cast<int>(start + lead) + 1});
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
}

std::vector<Cell> split_cells(std::string_view line) {
  std::vector<Cell> cells;
  split_cells(line, cells);
  return cells;
}

std::optional<double> parse_number(std::string_view s) {
  if (!s.empty() && s.front() == '+') {
    s.remove_prefix(1);
    if (!s.empty() && (s.front() == '+' || s.front() == '-')) return std::nullopt;
  }
  if (s.empty()) return std::nullopt;
  double v = 0.0;
  const std::from_chars_result r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

namespace {

bool is_metadata_key(std::string_view key) {
  if (key.empty()) return false;
  return std::all_of(key.begin(), key.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-' || c == '.';
  });
}

}  // namespace

std::optional<MetadataComment> parse_metadata_comment(std::string_view comment) {
  comment.remove_prefix(1);  // '#'
  const std::size_t colon = comment.find(':');
  if (colon == std::string_view::npos) return std::nullopt;
  const std::string_view key = trim(comment.substr(0, colon));
  if (!is_metadata_key(key)) return std::nullopt;
  return MetadataComment{key, trim(comment.substr(colon + 1))};
}

}  // namespace volmap::csv
