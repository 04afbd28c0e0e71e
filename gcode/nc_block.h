// One block (line) of an RS274NGC / ISO 6983 program, lexed.
//
// The whole text of the line is kept: a word records the byte span it came
// from, so a writer can replace a word and keep everything else (comments,
// spacing, N numbers, case) byte for byte. Lexing only: meaning is the
// interpreter's (nc_interpreter.h).
//
// G and M numbers are compared as scaled integers, never as floats (grbl):
// G38.2 -> 382, G1 -> 10, G59.3 -> 593.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace volmap::nc {

struct Word {
  char letter = 0;                   ///< upper case; '@' and '^' for polar radius and angle
  double value = 0.0;                ///< as written (program units)
  int code10 = -1;                   ///< G/M: value x 10 when it has at most one decimal, else -1
  std::uint32_t begin = 0, end = 0;  ///< byte span [begin, end) in Block::text
  int decimals = 0;                  ///< digits after the decimal point as written
};

struct Block {
  std::string text;           ///< the raw line, without its line ending
  int line = 0;               ///< 1-based physical line number
  bool block_delete = false;  ///< starts with '/'
  bool percent = false;       ///< a '%' program delimiter line
  std::vector<Word> words;    ///< in order of appearance, N words included
  std::string comment;        ///< text of the first ( ) comment (for MSG)
  /// The file the line is from, when not the program's own (a subroutine
  /// file of a flattened program); set by the caller after lexing.
  const std::string* file = nullptr;
  /// The line as the flattener evaluated it (parameters and expressions
  /// replaced by their values): columns are this text's, not the file's.
  bool evaluated = false;

  const Word* find(char letter) const {
    for (const Word& w : words)
      if (w.letter == letter) return &w;
    return nullptr;
  }
  bool has(char letter) const { return find(letter) != nullptr; }
};

/// Lexes one line (without its line ending). Throws InputError
/// ("file:line:column: ...; what to do") for what volmap does not read:
/// O-word control flow, # parameters, [ ] expressions, a letter without a
/// number, an unclosed comment, a character that is not G-code.
Block lex_block(std::string_view text, int line, const std::string& file);
/// The same into an existing block, reusing its storage (no allocation per
/// line once the buffers have grown: the streaming post's form).
void lex_block_into(std::string_view text, int line, const std::string& file, Block& b);

/// A line of axis words X Y Z only, in the form CAM writes them: each
/// letter at most once, in either case, its number [sign] digits [. digits]
/// (at most 15 digits) right after it, words separated by one space or
/// none, nothing before, between or after them; or the same after a G1
/// (G01, either case) and one space or none, as posts that write the motion
/// on every line give it. Most lines of a three-axis CAM program look like
/// this.
struct PlainAxisWords {
  double value[3] = {};  ///< by axis X Y Z, program units; as lex_block_into reads them
  unsigned given = 0;    ///< bit a: axis a has a word
  int count = 0;         ///< axis words
  /// The bytes of a leading G1 word and the space after it (the axis words
  /// begin there); 0: none.
  std::uint8_t g1 = 0;
  bool lower = false;   ///< the first letter is lower case (block_uses_lowercase)
  bool spaced = false;  ///< a space between two words, or a single word (block_uses_spaces)
};
/// Reads `text` (without its line ending) when it is such a line: true and
/// `out` set; false otherwise (out unspecified), also for a line
/// lex_block_into would refuse. Where it returns true, lex_block_into reads
/// the same words with the same values to the bit (tests/nc_test.cc); it
/// is the post-processor's shortcut past a Block.
bool lex_plain_axis_words(std::string_view text, PlainAxisWords& out);

}  // namespace volmap::nc
