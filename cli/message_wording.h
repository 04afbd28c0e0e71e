// The libraries name what a message is about by its field, in backquotes:
// `tolerance_um` (an option of the running command) or `verify.clamp` (an
// option of another one). A library user reads the field; the command line
// shows the flag to type: --tolerance-um, `volmap verify --clamp`. A field
// no command has stays as the library wrote it, backquotes and all, so a
// misnamed field shows in the message and in tests/cli/message_wording_test.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace volmap::cli {

/// `message` with each backquoted field that names an option of `verb` (or,
/// as `other.field`, of the command `other` of `app`) written as that
/// option: `field` -> --field-name, `other.field` -> volmap other --field.
std::string flag_wording(const std::string& message, const CLI::App& app, const CLI::App* verb);

/// For a command line CLI11 refused: a misspelt command or long option named,
/// with the nearest one ("'posst' is not a volmap command; did you mean
/// 'post'?"); empty when the line has neither.
std::string misspelling_hint(const CLI::App& app, int argc, const char* const* argv);

/// For an argument the command line did not expect: when it follows a flag
/// that takes no value (verify's --json writes to standard output, while
/// explain's names a file), says so; empty otherwise. `extras`: the
/// parser's message when it found arguments it did not expect (the hint
/// then needs the word after the flag among them); empty for any other
/// parse error, when the hint is given only for a command that takes no
/// positional input.
std::string flag_value_hint(const CLI::App& app, int argc, const char* const* argv,
                            const std::string& extras);

/// CLI11's range message in plain numbers: PositiveNumber's "Value -1 not in
/// range 0.000000 to 1797...(309 digits)" becomes "value -1 must be
/// positive".
std::string plain_range(const std::string& message);

}  // namespace volmap::cli
