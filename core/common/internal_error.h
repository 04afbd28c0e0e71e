// Exceptions volmap does not raise on purpose. Every exception that reaches
// main is a bug unless it is one of the errors the libraries raise for the
// user (is_expected_error); such a bug is reported as an internal error,
// with the file and line being read when the code that caught it knew them
// (InternalError), and a request to report it, never as a bare what().
#pragma once

#include <exception>
#include <stdexcept>
#include <string>

namespace volmap {

/// A position outside an error table or a volumetric table (the message
/// names the table and the range); the post and verify name the program's
/// line. A std::out_of_range of any other origin (`at()`) is a bug.
class OutsideTable : public std::out_of_range {
 public:
  using std::out_of_range::out_of_range;
};

/// Whether `e` is an error volmap raises on purpose for the user: an
/// InputError (file:line), an option value or a limit the libraries refuse
/// (std::invalid_argument and its subclasses, with a message of words, not
/// the standard library's "stoi"), OutsideTable, an output that cannot be
/// written (std::runtime_error itself, std::filesystem::filesystem_error).
/// Anything else (std::length_error, std::bad_alloc, std::out_of_range of
/// `at()`, a JSON library's exception, ...) is a bug.
bool is_expected_error(const std::exception& e) noexcept;

/// "std::length_error: basic_string::_M_create": the exception's type,
/// demangled, and its message.
std::string describe_exception(const std::exception& e);

/// An unexpected exception caught where the input's file and line (0: not
/// known) were known. what(): "internal error at FILE:LINE: TYPE: MESSAGE".
class InternalError : public std::runtime_error {
 public:
  InternalError(const std::string& file, int line, const std::exception& cause);
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_ = 0;
};

/// In a `catch (const std::exception& e)` that turns the errors it expects
/// into an InputError at file:line: throws InternalError(file, line, e)
/// when `e` is not one volmap raises on purpose (an InternalError already
/// made is thrown on as it is).
void throw_if_unexpected(const std::exception& e, const std::string& file, int line);

/// The one line main prints for an exception that is not expected: the
/// internal error, where it happened when known, and the request to report
/// it.
std::string internal_error_message(const std::exception& e);

}  // namespace volmap
