#include "tests/conformance/regression.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <stdexcept>

#include "tests/conformance/process.h"

namespace volmap::conformance {

namespace fs = std::filesystem;

namespace {

constexpr const char* kEnd = "; end of header\n";

std::string slug(const std::string& kind) {
  std::string s;
  for (char c : kind) {
    if (std::isalnum(static_cast<unsigned char>(c)))
      s += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    else if (!s.empty() && s.back() != '-')
      s += '-';
    if (s.size() >= 90) break;
  }
  while (!s.empty() && s.back() == '-') s.pop_back();
  return s;
}

std::string value(const std::string& header, const std::string& key) {
  const std::string k = "; " + key + ": ";
  const size_t at = header.find(k);
  if (at == std::string::npos) return "";
  const size_t from = at + k.size();
  return header.substr(from, header.find('\n', from) - from);
}

}  // namespace

std::string write_regression(const std::string& dir, const FailureCase& f) {
  std::string header = "; volmap conformance regression: " + f.finding.kind + "\n";
  header += "; field: " + f.finding.field + "\n";
  header += fmt::format("; tolerance_um: {}\n", f.tolerance_um);
  header += fmt::format("; seed: {} (volmap_conformance --replay {})\n", f.seed, f.seed);
  header += "; found: " + f.finding.detail + "\n";
  header += kEnd;
  const std::string name = fmt::format("{}-{}", slug(f.finding.kind), f.seed);
  fs::create_directories(dir);
  if (f.minimal.files.empty()) {
    const std::string path = (fs::path(dir) / (name + ".ngc")).string();
    write_file(path, header + f.minimal.main);
    return path;
  }
  const fs::path folder = fs::path(dir) / name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  write_file((folder / kProgramName).string(), header + f.minimal.main);
  for (const auto& [file, bytes] : f.minimal.files) write_file((folder / file).string(), bytes);
  return folder.string();
}

Regression read_regression(const std::string& path) {
  Regression r;
  r.path = path;
  const bool folder = fs::is_directory(path);
  const std::string text = read_file(folder ? (fs::path(path) / kProgramName).string() : path);
  const size_t end = text.find(kEnd);
  if (text.rfind("; volmap conformance regression: ", 0) != 0 || end == std::string::npos)
    throw std::runtime_error(path + ": not a conformance regression (no header)");
  const std::string header = text.substr(0, end);
  r.kind = header.substr(33, header.find('\n') - 33);
  r.field = value(header, "field");
  r.detail = value(header, "found");
  r.tolerance_um = std::stod(value(header, "tolerance_um"));
  r.program.main = text.substr(end + std::string(kEnd).size());
  if (folder)
    for (const auto& e : fs::directory_iterator(path))
      if (e.path().filename() != kProgramName)
        r.program.files.push_back({e.path().filename().string(), read_file(e.path().string())});
  std::sort(r.program.files.begin(), r.program.files.end());
  return r;
}

std::vector<std::string> regression_paths(const std::string& dir) {
  std::vector<std::string> v;
  if (!fs::is_directory(dir)) return v;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_directory() || e.path().extension() == ".ngc") v.push_back(e.path().string());
  std::sort(v.begin(), v.end());
  return v;
}

std::vector<Finding> rerun_regression(Judge& judge, const Regression& r) {
  const Judgement j =
      judge.judge(r.program, "regression", {FieldSpec::parse(r.field)}, r.tolerance_um);
  return j.failures;
}

}  // namespace volmap::conformance
