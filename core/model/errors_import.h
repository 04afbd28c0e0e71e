// Error sources in other formats than volmap's errors CSV (errors.md):
//
//  * ISG CSV (Beckhoff TF5280 / ISG kernel volumetric compensation): "//"
//    row comments, "#" breaks the file into blocks, each block a header row
//    and records, columns separated by blanks or tabs (commas and
//    semicolons accepted too). A component-error block's first column is
//    the argument (X Y Z in mm, A B C in degrees), the others ISO 230-1
//    component errors (EXX ...); a position-error block names location
//    errors without the E (C0X = EC0X, Y0A = EY0A; with the E accepted).
//    Values: translational mm, angular rad. Blocks with two arguments
//    (functional dependencies on another axis, "Z X EXX") are refused.
//  * Etalon exchange format, "Vendor" variant (what the ISG kernel reads):
//    INI-like sections "[NAME]" with "VALUE = v" for a position error or
//    "Gridpoints = { argument value ... }" for a component error; "//"
//    comments; same units as ISG. Sections whose name is no ISO 230-1
//    error are skipped (reported in ErrorSet::metadata["skipped"]).
//
// Both are translated into errors.md text (values to um / urad) and read by
// the volmap reader, so every rule of errors.md applies (strictly increasing
// positions, known names, finite numbers); its messages name the original
// file and line.
#pragma once

#include <iosfwd>
#include <string>

#include "core/model/error_set.h"

namespace volmap {

enum class ErrorsFormat { kAuto, kVolmap, kIsgCsv, kEtalon };

/// "auto", "volmap", "isg-csv", "etalon"; throws std::invalid_argument otherwise.
ErrorsFormat parse_errors_format(const std::string& name);
const char* errors_format_name(ErrorsFormat f);

/// Detection from the text: the first line that is neither blank nor a
/// comment starts with "[" -> Etalon; "//" comments, or a first such line
/// without a comma (blank- or tab-separated header) -> ISG CSV; else volmap.
/// A first line of one name alone ("EC0X", a one-column location block)
/// without "#" comments before it is either format: *ambiguous_line is then
/// its line number (else 0), and read_errors refuses it under kAuto.
ErrorsFormat detect_errors_format(const std::string& text, int* ambiguous_line = nullptr);

/// Translation into errors.md text; line_of[i] is the original line of the
/// translated line i + 1 (0: none). Throws InputError for structural
/// problems (file:line of the original).
std::string isg_csv_to_errors_csv(const std::string& text, const std::string& file,
                                  std::vector<int>& line_of);
std::string etalon_to_errors_csv(const std::string& text, const std::string& file,
                                 std::vector<int>& line_of, std::string* skipped = nullptr);

/// Reads errors in any of the formats (kAuto detects).
ErrorSet read_errors(std::istream& in, const std::string& file,
                     ErrorsFormat format = ErrorsFormat::kAuto);
/// Opens and reads `path` ("-" reads standard input).
ErrorSet load_errors(const std::string& path, ErrorsFormat format = ErrorsFormat::kAuto);

}  // namespace volmap
