// The NC language a program is written in: LinuxCNC's RS274NGC or the
// Fanuc / Haas dialect (ISO 6983 with Fanuc's rules and Custom Macro B).
// They read most blocks alike; where they differ (docs/post.md, "Dialects")
// a program read in the wrong one cuts something else, so the dialect is
// chosen before the first block: given (--dialect), or detected from the
// program's head.
#pragma once

#include <string>
#include <string_view>

namespace volmap::nc {

enum class Dialect { kAuto, kLinuxCnc, kFanuc };

/// "auto", "linuxcnc", "fanuc"; throws std::invalid_argument otherwise.
Dialect parse_dialect(std::string_view name);
const char* dialect_name(Dialect d);

/// What `auto` chose and why.
struct DialectChoice {
  Dialect dialect = Dialect::kLinuxCnc;
  bool detected = false;  ///< chosen by auto (else given)
  int line = 0;           ///< the line that decided, 0 when none did
  std::string reason;     ///< for stderr: "program number O1001 at line 2"
};

/// Fanuc when the program's first block (after '%' lines, blank and
/// comment-only lines, ( ) or ';') is a program number, `O1234` or `:1234` (with or
/// without a comment after it); LinuxCNC otherwise. A LinuxCNC program
/// never starts with a bare O number (LinuxCNC's O-words carry a keyword:
/// `O100 sub`). `head`: the program's first lines (a line cut at the end
/// of `head` is not looked at); `first_line`: the number of its first line.
DialectChoice detect_dialect(std::string_view head, int first_line);

/// Why a Fanuc block with text after ';' is refused (the interpreter's and
/// the macro flattener's word).
inline constexpr const char* kFanucTextAfterEndOfBlock =
    "';' with text after it: a Fanuc control reads ';' as the end of a block (EOB), not as a "
    "comment; put comments in ( ), or give --dialect linuxcnc for a LinuxCNC program";

/// Is `t` (one line) a Fanuc program number line: [N..] `O<digits>` or
/// `:<digits>`, then nothing but a comment? `digits` gets the number's text.
bool is_program_number_line(std::string_view t, std::string_view* digits = nullptr);

}  // namespace volmap::nc
