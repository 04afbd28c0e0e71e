// Machine definition files, format "volmap-machine/1" (docs/machine-format.md).
// Malformed JSON is reported with line and column; a valid document that does
// not describe a machine is reported with the JSON path of the offending value.
#pragma once

#include <iosfwd>
#include <string>

#include "core/model/machine.h"

namespace volmap {

Machine read_machine_json(std::istream& in, const std::string& file);
Machine load_machine_json(const std::string& path);

}  // namespace volmap
