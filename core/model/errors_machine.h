// Whether an errors file belongs to the machine it is used with. errors.md's
// metadata line "# machine: ..." names the machine the errors were measured
// on, by its machine file (as volmap identify and the samples write it) or
// by its name; errors of one machine applied to another give a plausible
// but wrong correction, so the commands that take both refuse a mismatch
// unless told otherwise (docs/errors-format.md).
#pragma once

#include <string>

#include "core/model/error_set.h"
#include "core/model/machine.h"

namespace volmap {

/// True when `named` (the value of "# machine:") names machine m loaded
/// from machine_path: equal to m's name, or a path whose file name without
/// extension is m's name or the machine file's, or the same file.
bool names_machine(const std::string& named, const Machine& m, const std::string& machine_path);

/// Throws InputError (the errors file, the line of "# machine:") naming both machines when the
/// errors'
/// "# machine:" line names another machine than m; errors without the line
/// (ISG CSV, Etalon, or a file that omits it) pass. `override_option` is
/// the option that skips the check, named in the message.
void require_errors_of_machine(const ErrorSet& errors, const Machine& m,
                               const std::string& machine_path, const std::string& override_option);

}  // namespace volmap
