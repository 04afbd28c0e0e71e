#include "core/common/input_file.h"

#include <cerrno>
#include <system_error>

#include "core/common/input_error.h"

namespace volmap {

std::ifstream open_input_file(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const std::string reason = std::generic_category().message(errno);
    throw InputError(
        path, 0, "cannot open " + what + " (" + reason + "); check the path and the permissions");
  }
  return in;
}

}  // namespace volmap
