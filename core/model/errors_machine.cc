#include "core/model/errors_machine.h"

#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>
#include <system_error>

#include "core/common/input_error.h"

namespace volmap {

namespace fs = std::filesystem;

bool names_machine(const std::string& named, const Machine& m, const std::string& machine_path) {
  if (named == m.name) return true;
  const fs::path p(named);
  if (p.stem().string() == m.name) return true;
  if (machine_path.empty()) return false;
  if (p.stem() == fs::path(machine_path).stem()) return true;
  std::error_code ec;
  return fs::equivalent(p, machine_path, ec) && !ec;
}

void require_errors_of_machine(const ErrorSet& errors, const Machine& m,
                               const std::string& machine_path,
                               const std::string& override_option) {
  const auto it = errors.metadata.find("machine");
  if (it == errors.metadata.end() || it->second.empty()) return;
  if (names_machine(it->second, m, machine_path)) return;
  const auto line = errors.metadata_line.find("machine");
  throw InputError(
      errors.file, line == errors.metadata_line.end() ? 0 : line->second,
      fmt::format("'# machine:' names {:?}, but the machine is {:?} ({}): errors measured on "
                  "another machine give a wrong correction; give this machine's errors, or {} "
                  "to use them anyway",
                  it->second, m.name, machine_path, override_option));
}

}  // namespace volmap
