// The text layer of volmap's CSV readers (errors.md, recordings.md, and the
// ISG CSV / Etalon importers that translate into errors.md): physical lines
// with the UTF-8 byte-order mark and the CR of CRLF removed, comma-separated
// cells that keep their 1-based character column, decimal numbers parsed
// the same way everywhere, and "# key: value" metadata comments.
//
// There is no quoting: a comma always separates cells. Blanks are ' ', '\t',
// '\f', '\v', '\r' and '\n'.
#pragma once

#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace volmap::csv {

bool is_space(char c);
/// `s` without leading and trailing blanks.
std::string_view trim(std::string_view s);
/// Only blanks.
bool is_blank(std::string_view line);
/// The first character that is not a blank is '#'.
bool is_comment(std::string_view line);

/// Physical lines of a text: the BOM of line 1 and a trailing CR removed.
class LineReader {
 public:
  /// `file` names the input in the message of a read error.
  LineReader(std::istream& in, std::string file);

  /// The next line into `text`; false at the end of the input. A read error
  /// of the stream is an InputError at the last line read.
  bool next(std::string& text);
  /// 1-based number of the last line read (0 before the first).
  int number() const { return number_; }

 private:
  std::istream& in_;
  std::string file_;
  int number_ = 0;
};

/// Every line of `text`, as LineReader reads them.
std::vector<std::string> split_lines(const std::string& text);

struct Cell {
  std::string_view text;  ///< trimmed
  int column = 0;         ///< 1-based character column of the cell's text
};

/// The comma-separated cells of `line` into `cells` (cleared first; reused
/// so that a reader's row loop does not allocate). A line always has at
/// least one cell; "a," has two, the second empty.
void split_cells(std::string_view line, std::vector<Cell>& cells);
std::vector<Cell> split_cells(std::string_view line);

/// A decimal number, locale-independent; a leading '+' is accepted. Returns
/// nothing unless the whole text is one number. NaN and infinity parse (the
/// caller judges them).
std::optional<double> parse_number(std::string_view s);

struct MetadataComment {
  std::string_view key;    ///< trimmed
  std::string_view value;  ///< trimmed
};

/// The key and value of a "# key: value" comment (`comment` trimmed, its
/// first character '#'); nothing when there is no colon or the key is not a
/// word of letters, digits, '_', '-' and '.' (prose that happens to hold a
/// colon).
std::optional<MetadataComment> parse_metadata_comment(std::string_view comment);

}  // namespace volmap::csv
