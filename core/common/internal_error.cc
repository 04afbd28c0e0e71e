#include "core/common/internal_error.h"

#include <cxxabi.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <typeinfo>

#include "core/common/input_error.h"

namespace volmap {
namespace {
std::string type_name(const std::exception& e) {
  const char* mangled = typeid(e).name();
  int status = 0;
  std::unique_ptr<char, void (*)(void*)> name(
      abi::__cxa_demangle(mangled, nullptr, nullptr, &status), std::free);
  std::string t = status == 0 && name ? std::string(name.get()) : std::string(mangled);
  // libstdc++'s inline namespace says nothing to a reader.
  for (std::size_t at; (at = t.find("::__cxx11")) != std::string::npos;) t.erase(at, 9);
  return t;
}

std::string one_line(std::string s) {
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

std::string where(const std::string& file, int line) {
  if (file.empty()) return std::string();
  return " at " + file + (line > 0 ? ":" + std::to_string(line) : std::string());
}
}  // namespace

bool is_expected_error(const std::exception& e) noexcept {
  if (dynamic_cast<const InternalError*>(&e)) return false;
  if (dynamic_cast<const InputError*>(&e) || dynamic_cast<const OutsideTable*>(&e)) return true;
  // The libraries' messages are sentences; std::stoi and its kin throw
  // std::invalid_argument with their own name as the message.
  if (dynamic_cast<const std::invalid_argument*>(&e)) return std::strchr(e.what(), ' ') != nullptr;
  if (dynamic_cast<const std::filesystem::filesystem_error*>(&e)) return true;
  return typeid(e) == typeid(std::runtime_error);
}

std::string describe_exception(const std::exception& e) {
  return one_line(type_name(e) + ": " + e.what());
}

InternalError::InternalError(const std::string& file, int line, const std::exception& cause)
    : std::runtime_error("internal error" + where(file, line) + ": " + describe_exception(cause)),
      file_(file),
      line_(line) {}

void throw_if_unexpected(const std::exception& e, const std::string& file, int line) {
  if (const auto* internal = dynamic_cast<const InternalError*>(&e)) throw *internal;
  if (!is_expected_error(e)) throw InternalError(file, line, e);
}

std::string internal_error_message(const std::exception& e) {
  const bool located = dynamic_cast<const InternalError*>(&e) != nullptr;
  std::string m = located ? one_line(e.what()) : "internal error: " + describe_exception(e);
  m += "; this is a bug in volmap, not a fault of the input: please report it with the command "
       "line and its input files";
  return m;
}

}  // namespace volmap
