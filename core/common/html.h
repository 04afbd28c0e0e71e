// Text placed into the self-contained HTML reports (explain, map, verify).
#pragma once

#include <string>
#include <string_view>

namespace volmap {

/// `text` with & < > " replaced by their character references, safe inside
/// an element and inside a double-quoted attribute.
std::string html_escape(std::string_view text);

}  // namespace volmap
