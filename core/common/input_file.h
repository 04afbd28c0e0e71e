// Opening a user's input file, with the one message for a file that cannot
// be opened; "-" reads standard input.
#pragma once

#include <fstream>
#include <iostream>
#include <string>

namespace volmap {

/// `path` opened for reading (binary: the readers strip CR themselves). A
/// file that cannot be opened is an InputError "PATH: cannot open WHAT
/// (reason); check the path and the permissions".
std::ifstream open_input_file(const std::string& path, const std::string& what);

/// `read(stream, name)` on standard input, named "<stdin>", when `path` is
/// "-"; otherwise on the file opened by open_input_file, named by its path.
template <typename Read>
auto read_input_file(const std::string& path, const std::string& what, Read read) {
  if (path == "-") return read(std::cin, std::string("<stdin>"));
  std::ifstream in = open_input_file(path, what);
  return read(in, path);
}

}  // namespace volmap
