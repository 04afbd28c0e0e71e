#include "gcode/block_words.h"

#include <fmt/format.h>

#include "core/common/input_error.h"
#include "gcode/g_codes.h"

namespace volmap::nc {
namespace {

// Letters whose words need nothing but "not twice in a block": all of A-Z
// except G and M (modal groups), N (may repeat), the axes the three-axis
// post refuses (A B C U V W: rotary words only where the machine has the
// axis) and E (refused); '@' '^' are handled apart.
constexpr std::array<bool, 256> kPlainLetter = [] {
  std::array<bool, 256> t{};
  for (char c = 'A'; c <= 'Z'; ++c) t[static_cast<unsigned char>(c)] = true;
  for (char c : {'G', 'M', 'N', 'A', 'B', 'C', 'U', 'V', 'W', 'E'})
    t[static_cast<unsigned char>(c)] = false;
  return t;
}();

void collect_g_word(const Block& b, const std::string& file, const Word& w, BlockWords& out) {
  const char* why = nullptr;
  const int grp = w.code10 < 0 ? -1 : g_group(w.code10, &why);
  if (grp < 0)
    refuse_block(
        file, b, &w,
        fmt::format("G{} is not supported: {}", b.text.substr(w.begin + 1, w.end - w.begin - 1),
                    why ? why : "unknown G code"));
  if (out.g_mask & (1u << grp)) {
    // LinuxCNC reads G80 beside another motion code as that code alone, in
    // either order (`G0 X1 G80`, the safety line `G00 G17 G21 G40 G49 G80
    // G90` of many CAM posts; checked with rs274): the other code ends any
    // canned cycle anyway.
    const Word* before = out.g[static_cast<size_t>(grp)];
    if (grp == kMotion && w.code10 == kG80CycleCancel && before->code10 != kG80CycleCancel) return;
    if (grp == kMotion && before->code10 == kG80CycleCancel && w.code10 != kG80CycleCancel) {
      out.g[static_cast<size_t>(grp)] = &w;
      return;
    }
    refuse_block(file, b, &w,
                 "two G codes of the same modal group in one block; put them in separate blocks");
  }
  // (A second non-modal code failed just above: the group's bit was set.)
  if (grp == kNonModal && (out.g_mask & (1u << kNonModal)) && out.g[kNonModal]->code10 != w.code10)
    refuse_block(file, b, &w, "two non-modal G codes in one block; split the block");
  out.g_mask |= 1u << grp;
  out.g[static_cast<size_t>(grp)] = &w;
}

void collect_m_word(const Block& b, const std::string& file, const Word& w, BlockWords& out) {
  const char* why = nullptr;
  const int grp = w.code10 < 0 ? -1 : m_group(w.code10, &why);
  if (grp < 0)
    refuse_block(file, b, &w,
                 fmt::format("M code is not supported: {}", why ? why : "unknown M code"));
  if (grp != kMOther && (out.m_mask & (1u << grp)))
    refuse_block(file, b, &w, "two M codes of the same modal group in one block; split the block");
  out.m_mask |= 1u << grp;
  out.m[static_cast<size_t>(grp)] = &w;
}

// A word of another letter than the plain ones, G and M.
void collect_other_word(const Block& b, const std::string& file, const std::string& rotary_axes,
                        const Word& w, BlockWords& out) {
  if (w.letter == '@' || w.letter == '^') {
    const Word*& slot = w.letter == '@' ? out.polar_radius : out.polar_angle;
    if (slot)
      refuse_block(file, b, &w, fmt::format("word {} appears twice in one block", w.letter));
    slot = &w;
    return;
  }
  const char L = w.letter;
  const bool rotary = L == 'A' || L == 'B' || L == 'C';
  if ((rotary || L == 'U' || L == 'V' || L == 'W') && rotary_axes.empty())
    refuse_block(file, b, &w,
                 fmt::format("axis word {} is not supported by the three-axis post-processor; "
                             "use a five-axis machine definition",
                             L));
  if ((rotary && rotary_axes.find(L) == std::string::npos) || L == 'U' || L == 'V' || L == 'W')
    refuse_block(file, b, &w, fmt::format("the machine has no axis {}", L));
  if (L == 'E') refuse_block(file, b, &w, "word E is not supported (a lathe's)");
  if (L != 'N' && (out.letter_mask & (1u << (L - 'A'))))
    refuse_block(file, b, &w, fmt::format("word {} appears twice in one block", L));
  out.letter[static_cast<size_t>(L - 'A')] = &w;
  out.letter_mask |= 1u << (L - 'A');
}

}  // namespace

void refuse_block(const std::string& file, const Block& b, const Word* w, const std::string& msg) {
  const std::string& from = b.file ? *b.file : file;
  if (b.evaluated)  // a column of the evaluated text would point nowhere in the file
    throw InputError(from, b.line, 0, msg + " (in the evaluated block \"" + b.text + "\")");
  throw InputError(from, b.line, w ? static_cast<int>(w->begin) + 1 : 0, msg);
}

void BlockWords::null_unfilled() {
  for (size_t k = 0; k < letter.size(); ++k)
    if (!(letter_mask & (1u << k))) letter[k] = nullptr;
  for (size_t k = 0; k < g.size(); ++k)
    if (!(g_mask & (1u << k))) g[k] = nullptr;
  for (size_t k = 0; k < m.size(); ++k)
    if (!(m_mask & (1u << k))) m[k] = nullptr;
}

void collect_block_words(const Block& b, const std::string& file, const std::string& rotary_axes,
                         BlockWords& out) {
  out.polar_radius = out.polar_angle = nullptr;
  out.g_mask = out.m_mask = 0;
  out.letter_mask = 0;
  for (const Word& w : b.words) {
    // Most words are plain letters (X Y Z F ...): one test sends them on.
    if (kPlainLetter[static_cast<unsigned char>(w.letter)]) {
      const size_t L = static_cast<size_t>(w.letter - 'A');
      if (out.letter_mask & (1u << L))
        refuse_block(file, b, &w, fmt::format("word {} appears twice in one block", w.letter));
      out.letter[L] = &w;
      out.letter_mask |= 1u << L;
      continue;
    }
    if (w.letter == 'G')
      collect_g_word(b, file, w, out);
    else if (w.letter == 'M')
      collect_m_word(b, file, w, out);
    else
      collect_other_word(b, file, rotary_axes, w, out);
  }
}

}  // namespace volmap::nc
