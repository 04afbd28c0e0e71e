// Reader for the component and location errors CSV, version 1
// (spec: shared/spec/errors.md). Units are converted here and only here:
// positions mm / degree -> mm / rad; errors um / urad -> mm / rad.
#pragma once

#include <iosfwd>
#include <string>

#include "core/model/error_set.h"

namespace volmap {

/// Parses an errors CSV. `file` names the input in messages. Throws
/// InputError ("file:line: ...") on every bad-input rule of the spec.
ErrorSet read_errors_csv(std::istream& in, const std::string& file);

/// Opens and parses `path` ("-" reads standard input).
ErrorSet load_errors_csv(const std::string& path);

}  // namespace volmap
