// Reading typed values from user JSON documents (plans, effects) with errors
// that name the file and the JSON path of the offending value
// ("plan.json:/tests/0/step: expected a number > 0"), or the line and column
// of malformed JSON.
#pragma once

#include <Eigen/Core>
#include <initializer_list>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "core/common/axis_name.h"

namespace volmap {

/// Parses a whole JSON document; malformed text is an InputError at
/// file:line:column.
nlohmann::json parse_json_document(std::istream& in, const std::string& file);

/// Line and column (1-based) in `text` of the position nlohmann's
/// parse_error reports (its `byte`: 1-based, the character it stopped at).
std::pair<int, int> json_error_line_column(const std::string& text, std::size_t byte);

/// For a parse that failed with nlohmann's out_of_range (error 406: a number
/// too large for a double, which carries no position): InputError at the
/// line and column of the first such number in `text`.
[[noreturn]] void throw_json_number_overflow(const std::string& text, const std::string& file);

/// The message for `key`, which an object that takes only `allowed` does
/// not: the nearest allowed key first when one is close (a typo: at most
/// max(3, length / 3) single-character edits away), then the list.
std::string unknown_key_message(const std::string& key, std::initializer_list<const char*> allowed);

/// A JSON object at a path, with typed accessors that throw InputError.
class JsonObject {
 public:
  JsonObject(const std::string& file, const nlohmann::json& value, std::string path);

  const std::string& path() const { return path_; }
  std::string path_of(const std::string& key) const { return path_ + "/" + key; }
  bool has(const std::string& key) const { return value_.contains(key); }
  std::vector<std::string> keys() const;  ///< in document order (sorted by nlohmann)
  const nlohmann::json& at(const std::string& key) const;  ///< required

  /// Every key must be one of `allowed` (a typo is an error, not ignored).
  void allow_only(std::initializer_list<const char*> allowed) const;

  double number(const std::string& key) const;
  double number_or(const std::string& key, double fallback) const;
  std::string string(const std::string& key) const;
  std::string string_or(const std::string& key, const std::string& fallback) const;
  bool boolean_or(const std::string& key, bool fallback) const;
  AxisName axis(const std::string& key) const;
  Eigen::Vector3d vec3(const std::string& key) const;
  /// A number, an array of numbers, or {"from", "to", "step"} (inclusive;
  /// descending when from > to).
  std::vector<double> values(const std::string& key) const;
  JsonObject object(const std::string& key) const;
  std::vector<JsonObject> objects(const std::string& key) const;  ///< array of objects

  [[noreturn]] void fail(const std::string& key, const std::string& message) const;

 private:
  double number_at(const nlohmann::json& v, const std::string& path) const;
  std::string file_;
  const nlohmann::json& value_;
  std::string path_;
};

}  // namespace volmap
