// The Fanuc / Haas dialect's own rules for a block (docs/post.md,
// "Dialects"), after Fanuc's Series 0i-MF operator's manual (B-64604EN):
// - "Decimal point programming": an address that takes a distance or an
//   angle (X Y Z A B C I J K R Q) written without a decimal point counts
//   least input increments (X10 = 0.010 mm on an IS-B metric control)
//   unless parameter 3401#0 (DPI) makes it a whole unit. Which one a
//   machine has is not in the program, so a non-zero value without a point
//   is refused; X0 means the same either way.
// - G04 dwell: the time is X (seconds) or P (milliseconds), not an axis.
// - Canned cycles are group 09 and G80 cancels them; the group 01 motion
//   (G00 G01 G02 G03) stays in effect (State::group01). K is the number of
//   repeats (L on Haas and older controls).
#include <fmt/format.h>

#include <cstdint>
#include <cstring>

#include "gcode/block_check.h"
#include "gcode/g_codes.h"

namespace volmap::nc {
namespace {

bool written_with_point(const Block& b, const Word& w) {
  return std::memchr(b.text.data() + w.begin, '.', w.end - w.begin) != nullptr;
}

}  // namespace

void BlockCheck::fanuc_words() {
  // ';' is the end of a block (EOB) as a Fanuc control shows it, not a
  // comment: alone at the end it ends the block; text after it is refused.
  char close = 0;
  for (std::size_t k = 0; k < b_.text.size(); ++k) {
    const char c = b_.text[k];
    if (close) {
      close = c == close ? 0 : close;
    } else if (c == '(') {
      close = ')';
    } else if (c == ';' && b_.text.find_first_not_of(" \t\r;", k) != std::string::npos) {
      Word at;  // (a place for the message's column)
      at.begin = static_cast<std::uint32_t>(k);
      refuse_block(file_, b_, &at, kFanucTextAfterEndOfBlock);
    }
  }
  const bool dwell = (words_.g_mask & (1u << kNonModal)) != 0 && g[kNonModal]->code10 == kG4Dwell;
  // H is modal on a Fanuc control: G43 without H keeps the last one, an H
  // alone under G43 switches to it. Both refused: give G43 with its H.
  const bool g43 =
      (words_.g_mask & (1u << kToolLength)) != 0 && g[kToolLength]->code10 == kG43ToolLength;
  if (g43 && !words_.given_word('H'))
    fail(g[kToolLength],
         "G43 without H: a Fanuc control applies the H number in effect (the "
         "last one given), which volmap does not follow; give G43 H<n>");
  if (const Word* h = words_.given_word('H'); h && !g43)
    fail(h,
         "H without G43: on a Fanuc control it selects another tool length offset while G43 "
         "is in effect; give G43 H<n>");
  const bool motion_word = (words_.g_mask & (1u << kMotion)) != 0;
  const bool cycle = is_cycle(motion_word ? g[kMotion]->code10 : s_.motion);
  for (const Word& w : b_.words) {
    if (!std::strchr("XYZABCIJKRQ", w.letter) || w.value == 0.0) continue;
    if (dwell && w.letter == 'X' && written_with_point(b_, w)) continue;  // seconds
    if (dwell && w.letter == 'X')
      fail(&w,
           "G04 X without a decimal point counts least input increments (X2 = 0.002 s) "
           "unless parameter 3401#0 is set; write the seconds with a point, or P in ms");
    if (cycle && w.letter == 'K') continue;   // repeats
    if (written_with_point(b_, w)) continue;  // (the flattener writes its values so)
    fail(&w,
         fmt::format("{} has no decimal point: a Fanuc control reads it in least input "
                     "increments ({}{} = {:g} mm on a metric IS-B control) unless parameter "
                     "3401#0 (DPI) is set, and which one this machine has is not in the "
                     "program; write {}{}. (with the point) for {:g} units, or {}{:g}",
                     w.letter, w.letter, b_.text.substr(w.begin + 1, w.end - w.begin - 1),
                     w.value * 0.001, w.letter, b_.text.substr(w.begin + 1, w.end - w.begin - 1),
                     w.value, w.letter, w.value * 0.001));
  }
  if (dwell) {
    // The time is not an axis: taken out of the axis words (X seconds or
    // P milliseconds; the block moves nothing and is written as it is).
    if (const Word* x = words_.given_word('X')) {
      if (words_.given_word('P')) fail(x, "G04 with both X and P; give the dwell time once");
      words_.letter[static_cast<size_t>('X' - 'A')] = nullptr;
      words_.letter_mask &= ~(1u << ('X' - 'A'));
      dwell_time_given_ = true;
    }
  }
}

}  // namespace volmap::nc
