// How the files maps/ writes (tables, factorized tables, exports, the map
// report) word their errors: the wording they have always had, which the
// bad-input goldens check. "-" is a file name here: the verbs write standard
// output themselves.
#pragma once

#include "core/common/atomic_file.h"

namespace volmap::maps {

inline constexpr AtomicOutputWording kOutputWording{
    .dash_is_stdout = false,
    .cannot_create =
        "{path}: cannot create the file ({reason}); check the folder exists and is writable",
    .write_error = "{path}: write error (disk full?)",
    .cannot_rename = "{path}: cannot rename the temporary file onto it ({reason})",
    .output_is_input = "{output}: the output is the input file {input}; write to another path",
};

}  // namespace volmap::maps
