// Regression files of the conformance engine (engine.h): a minimal failing
// program with a header of `;` comment lines (the class, the error field,
// the tolerance, the seed, what was seen), up to `; end of header`, which
// is taken off before the program is judged. A program with subroutine
// files is a folder: NAME/prog.ngc beside them.
#pragma once

#include <string>

#include "tests/conformance/engine.h"

namespace volmap::conformance {

/// Writes the failure's minimal program under `dir`; returns its path.
std::string write_regression(const std::string& dir, const FailureCase& failure);

}  // namespace volmap::conformance
