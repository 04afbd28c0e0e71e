// Errors in user files: one policy for the whole input layer.
//
// A user file that cannot be read raises InputError. Its message is one line,
// "FILE:LINE: what is wrong; what to do", which the CLI prints unchanged and
// exits with status 1. Line and column are 1-based; 0 means "not known" and
// is left out of the message. JSON inputs use a JSON path in place of a line.
#pragma once

#include <stdexcept>
#include <string>

namespace volmap {

class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, int line, const std::string& message);
  InputError(const std::string& file, int line, int column, const std::string& message);
  /// For JSON documents: `where` is a JSON path such as "/axes/2/travel".
  static InputError at_json_path(const std::string& file, const std::string& json_path,
                                 const std::string& message);

  const std::string& file() const { return file_; }
  int line() const { return line_; }
  int column() const { return column_; }

 private:
  InputError(std::string file, int line, int column, std::string where, const std::string& message);
  std::string file_;
  int line_ = 0;
  int column_ = 0;
};

}  // namespace volmap
