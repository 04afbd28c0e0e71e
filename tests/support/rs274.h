// Running LinuxCNC's standalone interpreter from the tests. rs274 keeps its
// tool table in $HOME/.tool.mmap, created and truncated by every run: two
// runs at once (tests of one ctest -j, or two test runs on one machine)
// would share and clobber it. Each test process gets a HOME of its own
// under its temporary folder.
#pragma once

#include <string>

#include "tests/support/cli_in_source.h"

namespace volmap::test {

/// "HOME=<this process's own folder> rs274 " + args, for std::system.
inline std::string rs274_command(const std::string& args) {
  static const std::string home = fresh_dir("rs274_home").string();
  return "HOME=" + home + " rs274 " + args;
}

}  // namespace volmap::test
