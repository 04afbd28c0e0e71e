#include "core/common/input_error.h"

#include <utility>

namespace volmap {
namespace {
std::string compose(const std::string& file, int line, int column, const std::string& where,
                    const std::string& message) {
  std::string out = file.empty() ? std::string("<input>") : file;
  if (!where.empty()) {
    out += ':';
    out += where;
  } else if (line > 0) {
    out += ':';
    out += std::to_string(line);
    if (column > 0) {
      out += ':';
      out += std::to_string(column);
    }
  }
  out += ": ";
  out += message;
  // One line, always: a message must never break a script's line parser.
  for (char& c : out)
    if (c == '\n' || c == '\r') c = ' ';
  return out;
}
}  // namespace

InputError::InputError(std::string file, int line, int column, std::string where,
                       const std::string& message)
    : std::runtime_error(compose(file, line, column, where, message)),
      file_(std::move(file)),
      line_(line),
      column_(column) {}

InputError::InputError(const std::string& file, int line, const std::string& message)
    : InputError(file, line, 0, std::string(), message) {}

InputError::InputError(const std::string& file, int line, int column, const std::string& message)
    : InputError(file, line, column, std::string(), message) {}

InputError InputError::at_json_path(const std::string& file, const std::string& json_path,
                                    const std::string& message) {
  return InputError(file, 0, 0, json_path.empty() ? "/" : json_path, message);
}

}  // namespace volmap
