// The samples an installed volmap carries (cmake --install puts them under
// <prefix>/share/volmap/samples): an input named samples/... that is not in
// the current folder is taken from there, with a note on stderr, so the
// examples of every --help run from any folder. Outputs are never
// redirected, and nothing changes in a build tree (no share/ beside bin/).
#pragma once

#include <string>
#include <vector>

namespace volmap::cli {

/// The installed samples folder (canonical), or empty when volmap is not
/// installed (the executable's ../share/volmap/samples does not exist).
std::string installed_samples_dir();

/// argv with every input argument "samples/..." (or "--opt=samples/...")
/// that does not exist here but does in `samples_dir` replaced by the
/// installed file; notes one line per replacement into *notes. Values of
/// -o, --output, --report and --json (outputs) are left alone.
std::vector<std::string> with_installed_samples(const std::vector<std::string>& args,
                                                const std::string& samples_dir,
                                                std::vector<std::string>* notes);

}  // namespace volmap::cli
