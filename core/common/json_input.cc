#include "core/common/json_input.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <istream>
#include <iterator>
#include <string_view>

#include "core/common/input_error.h"

namespace volmap {

std::pair<int, int> json_error_line_column(const std::string& text, std::size_t byte) {
  int line = 1, column = 1;
  for (std::size_t i = 0; i + 1 < byte && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

nlohmann::json parse_json_document(std::istream& in, const std::string& file) {
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    const auto [line, column] = json_error_line_column(text, e.byte);
    std::string what = e.what();
    const std::size_t colon = what.rfind(": ");
    if (colon != std::string::npos) what = what.substr(colon + 2);
    throw InputError(file, line, column, "malformed JSON (" + what + "); fix the syntax");
  } catch (const nlohmann::json::out_of_range&) {
    throw_json_number_overflow(text, file);
  }
}

void throw_json_number_overflow(const std::string& text, const std::string& file) {
  int line = 1, column = 1;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\')
        ++i, ++column;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '-' || (c >= '0' && c <= '9')) {
      std::size_t end = i;
      while (end < text.size() &&
             std::string_view("+-.eE0123456789").find(text[end]) != std::string_view::npos)
        ++end;
      const std::string number = text.substr(i, end - i);
      if (!std::isfinite(std::strtod(number.c_str(), nullptr)))
        throw InputError(file, line, column,
                         fmt::format("number {} is too large for a double; give a finite number",
                                     number.size() > 40 ? number.substr(0, 40) + "..." : number));
      column += static_cast<int>(end - i);
      i = end - 1;
      continue;
    }
    if (c == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  throw InputError(file, 0, "a number is too large for a double; give finite numbers");
}

JsonObject::JsonObject(const std::string& file, const nlohmann::json& value, std::string path)
    : file_(file), value_(value), path_(std::move(path)) {
  if (!value_.is_object()) throw InputError::at_json_path(file_, path_, "expected an object {...}");
}

void JsonObject::fail(const std::string& key, const std::string& message) const {
  throw InputError::at_json_path(file_, key.empty() ? path_ : path_of(key), message);
}

const nlohmann::json& JsonObject::at(const std::string& key) const {
  auto it = value_.find(key);
  if (it == value_.end()) fail("", fmt::format("missing required key \"{}\"", key));
  return *it;
}

std::vector<std::string> JsonObject::keys() const {
  std::vector<std::string> out;
  for (auto it = value_.begin(); it != value_.end(); ++it) out.push_back(it.key());
  return out;
}

namespace {

// Levenshtein distance (insertions, deletions, substitutions).
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

}  // namespace

std::string unknown_key_message(const std::string& key,
                                std::initializer_list<const char*> allowed) {
  std::string list, nearest;
  std::size_t best = std::max<std::size_t>(3, key.size() / 3) + 1;
  for (const char* a : allowed) {
    list += std::string(list.empty() ? "" : ", ") + a;
    const std::size_t d = edit_distance(key, a);
    if (d < best) {
      best = d;
      nearest = a;
    }
  }
  if (nearest.empty()) return fmt::format("unknown key \"{}\"; expected one of: {}", key, list);
  return fmt::format("unknown key \"{}\"; did you mean \"{}\"? (expected one of: {})", key, nearest,
                     list);
}

void JsonObject::allow_only(std::initializer_list<const char*> allowed) const {
  for (auto it = value_.begin(); it != value_.end(); ++it) {
    bool ok = false;
    for (const char* a : allowed) ok = ok || it.key() == a;
    if (!ok) fail(it.key(), unknown_key_message(it.key(), allowed));
  }
}

double JsonObject::number_at(const nlohmann::json& v, const std::string& path) const {
  if (!v.is_number()) throw InputError::at_json_path(file_, path, "expected a number");
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw InputError::at_json_path(file_, path, "expected a finite number");
  return x;
}

double JsonObject::number(const std::string& key) const { return number_at(at(key), path_of(key)); }

double JsonObject::number_or(const std::string& key, double fallback) const {
  return has(key) ? number(key) : fallback;
}

std::string JsonObject::string(const std::string& key) const {
  const nlohmann::json& v = at(key);
  if (!v.is_string()) fail(key, "expected a string");
  return v.get<std::string>();
}

std::string JsonObject::string_or(const std::string& key, const std::string& fallback) const {
  return has(key) ? string(key) : fallback;
}

bool JsonObject::boolean_or(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const nlohmann::json& v = at(key);
  if (!v.is_boolean()) fail(key, "expected true or false");
  return v.get<bool>();
}

AxisName JsonObject::axis(const std::string& key) const {
  const std::string s = string(key);
  std::optional<AxisName> a;
  if (s.size() == 1) a = axis_from_char(s[0]);
  if (!a) fail(key, fmt::format("\"{}\" is not an axis; expected one of X, Y, Z, A, B, C", s));
  return *a;
}

Eigen::Vector3d JsonObject::vec3(const std::string& key) const {
  const nlohmann::json& v = at(key);
  if (!v.is_array() || v.size() != 3) fail(key, "expected an array of three numbers [x, y, z]");
  return {number_at(v[0], path_of(key) + "/0"), number_at(v[1], path_of(key) + "/1"),
          number_at(v[2], path_of(key) + "/2")};
}

std::vector<double> JsonObject::values(const std::string& key) const {
  const nlohmann::json& v = at(key);
  const std::string p = path_of(key);
  std::vector<double> out;
  if (v.is_number()) {
    out.push_back(number_at(v, p));
  } else if (v.is_array()) {
    if (v.empty()) fail(key, "expected at least one value");
    for (std::size_t k = 0; k < v.size(); ++k)
      out.push_back(number_at(v[k], p + "/" + std::to_string(k)));
  } else if (v.is_object()) {
    const JsonObject r(file_, v, p);
    r.allow_only({"from", "to", "step"});
    const double from = r.number("from"), to = r.number("to"), step = r.number("step");
    if (!(step > 0)) r.fail("step", "expected a number > 0");
    const double span = std::abs(to - from);
    const auto n = static_cast<long long>(std::floor(span / step + 1e-9));
    if (n > 10'000'000) r.fail("step", "too many points; use a larger step");
    const double sign = to >= from ? 1.0 : -1.0;
    for (long long k = 0; k <= n; ++k) out.push_back(from + sign * static_cast<double>(k) * step);
  } else {
    fail(key, "expected a number, an array of numbers, or {\"from\", \"to\", \"step\"}");
  }
  return out;
}

JsonObject JsonObject::object(const std::string& key) const {
  return JsonObject(file_, at(key), path_of(key));
}

std::vector<JsonObject> JsonObject::objects(const std::string& key) const {
  const nlohmann::json& v = at(key);
  if (!v.is_array()) fail(key, "expected an array of objects");
  std::vector<JsonObject> out;
  for (std::size_t k = 0; k < v.size(); ++k)
    out.emplace_back(file_, v[k], path_of(key) + "/" + std::to_string(k));
  return out;
}

}  // namespace volmap
