#include "gcode/program_reader.h"

#include <algorithm>
#include <array>
#include <cstring>

#include "core/common/input_error.h"
#include "gcode/nc_interpreter.h"

namespace volmap::nc {
namespace {

constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";

std::string_view trimmed(std::string_view t) {
  while (!t.empty() && (t.front() == ' ' || t.front() == '\t')) t.remove_prefix(1);
  while (!t.empty() && (t.back() == ' ' || t.back() == '\t' || t.back() == '\r'))
    t.remove_suffix(1);
  return t;
}

bool is_percent_line(std::string_view t) {
  t = trimmed(t);
  return !t.empty() && t.front() == '%';
}

// The characters that can make a line more than a block of literal words:
// '#' '[' (parameters, expressions), 'O' (O-words), 'M' (M98/M99), '%'.
// Most lines have none: one look per character, then nothing else.
constexpr std::array<bool, 256> kNotPlain = [] {
  std::array<bool, 256> t{};
  for (unsigned char c : {'#', '[', 'O', 'o', 'M', 'm', '%'}) t[c] = true;
  return t;
}();
bool maybe_special(std::string_view t) {
  for (const char c : t)
    if (kNotPlain[static_cast<unsigned char>(c)]) return true;
  return false;
}
}  // namespace

bool needs_flattening(std::string_view t) {
  if (!maybe_special(t)) return false;
  // An O-word begins the block (after '/' and an N number).
  std::size_t i = 0;
  auto skip = [&] {
    while (i < t.size() && (t[i] == ' ' || t[i] == '\t')) ++i;
  };
  skip();
  if (i < t.size() && t[i] == '/') ++i, skip();
  if (i < t.size() && (t[i] == 'N' || t[i] == 'n')) {
    ++i;
    while (i < t.size() &&
           ((t[i] >= '0' && t[i] <= '9') || t[i] == ' ' || t[i] == '\t' || t[i] == '.'))
      ++i;
  }
  if (i < t.size() && (t[i] == 'O' || t[i] == 'o')) return true;
  // M98 / M99 (Fanuc-style subprograms, which LinuxCNC runs).
  for (const char letter : {'M', 'm'}) {
    std::size_t at = 0;
    while (const void* m = std::memchr(t.data() + at, letter, t.size() - at)) {
      std::size_t k = static_cast<std::size_t>(static_cast<const char*>(m) - t.data()) + 1;
      at = k;
      while (k < t.size() && (t[k] == ' ' || t[k] == '\t' || t[k] == '0')) ++k;
      if ((t.substr(k, 2) == "98" || t.substr(k, 2) == "99") &&
          (k + 2 >= t.size() || t[k + 2] < '0' || t[k + 2] > '9'))
        return true;
    }
  }
  const void* hash = std::memchr(t.data(), '#', t.size());
  const void* bracket = std::memchr(t.data(), '[', t.size());
  if (!hash && !bracket) return false;
  // Outside comments only.
  char close = 0;
  for (char c : t) {
    if (close) {
      if (c == close) close = 0;
    } else if (c == '(') {
      close = ')';
    } else if (c == ';') {
      return false;
    } else if (c == '#' || c == '[') {
      return true;
    }
  }
  return false;
}

bool fanuc_needs_flattening(std::string_view t) {
  if (is_program_number_line(t)) return false;  // (the reader's: written as it is)
  if (needs_flattening(t)) return true;
  flatten::NormalizedLine n;
  flatten::normalize(t, n);
  const std::string& x = n.text;
  std::size_t i = !x.empty() && x[0] == '/' ? 1 : 0;
  if (i < x.size() && x[i] == 'n')
    while (++i < x.size() && x[i] >= '0' && x[i] <= '9') {
    }
  const std::string_view rest = std::string_view(x).substr(i);
  for (std::string_view kw : {"if[", "while[", "goto", "do", "end"})
    if (rest.starts_with(kw)) return true;
  // G65 / G66 anywhere outside comments (normalize() kept them as written).
  char close = 0;
  for (std::size_t k = 0; k + 2 < x.size(); ++k) {
    if (close) {
      if (x[k] == close) close = 0;
    } else if (x[k] == '(') {
      close = ')';
    } else if (x[k] == 'g') {
      std::size_t d = k + 1;
      while (d < x.size() && x[d] == '0') ++d;
      if (x.compare(d, 2, "65") == 0 || x.compare(d, 2, "66") == 0) return true;
    }
  }
  return false;
}

ProgramReader::ProgramReader(std::istream& in, std::string file, Interpreter& interp,
                             std::vector<std::string> subroutine_path)
    : in_(in),
      file_(std::move(file)),
      interp_(interp),
      path_(std::move(subroutine_path)),
      buf_(std::size_t{1} << 16) {}

ProgramReader::~ProgramReader() = default;

void ProgramReader::fill() {
  const std::size_t rest = end_ - begin_;
  std::memmove(buf_.data(), buf_.data() + begin_, rest);
  begin_ = 0;
  end_ = rest;
  if (end_ == buf_.size()) buf_.resize(2 * buf_.size());
  in_.read(buf_.data() + end_, static_cast<std::streamsize>(buf_.size() - end_));
  const auto got = static_cast<std::size_t>(in_.gcount());
  end_ += got;
  if (got == 0) eof_ = true;
}

bool ProgramReader::physical(std::string_view& text, bool& newline) {
  // Lines out of a large buffer (getline's per-line work and copies
  // avoided); the buffer grows only to hold the longest line.
  for (;;) {
    const char* nl =
        static_cast<const char*>(std::memchr(buf_.data() + begin_, '\n', end_ - begin_));
    if (nl) {
      const auto at = static_cast<std::size_t>(nl - buf_.data());
      text = std::string_view(buf_.data() + begin_, at - begin_);
      newline = true;
      begin_ = at + 1;
      ++number_;
      return true;
    }
    if (eof_) {
      if (begin_ == end_) return false;
      text = std::string_view(buf_.data() + begin_, end_ - begin_);
      newline = false;
      begin_ = end_;
      ++number_;
      return true;
    }
    fill();
  }
}

void ProgramReader::find_leader() {
  // Leader: text before a first '%' that is not the first line. Looked for
  // in the first piece read (64 KiB): a tape's leader is a few lines.
  while (!eof_ && end_ < buf_.size()) fill();
  std::string_view head(buf_.data() + begin_, end_ - begin_);
  if (head.starts_with(kByteOrderMark)) {
    // An encoding's mark, not G-code: not read, handed out verbatim (the
    // output begins as the input did).
    report_.byte_order_mark = true;
    begin_ += kByteOrderMark.size();
    head.remove_prefix(kByteOrderMark.size());
  }
  int lines = 0;
  bool text_before = false;
  std::size_t b = 0;
  while (b < head.size()) {
    std::size_t e = head.find('\n', b);
    if (e == std::string_view::npos) {
      if (!eof_) return;  // a line longer than the piece: no leader
      e = head.size();
    }
    const std::string_view l = head.substr(b, e - b);
    if (is_percent_line(l)) {
      if (text_before) leader_left_ = report_.leader_lines = lines;
      return;
    }
    text_before = text_before || !trimmed(l).empty();
    ++lines;
    b = e + 1;
  }
}

void ProgramReader::choose_dialect() {
  const Dialect given = interp_.setup().dialect;
  // The head as find_leader() left it (the leader, not run, skipped).
  std::string_view head(buf_.data() + begin_, end_ - begin_);
  for (int k = 0; k < leader_left_; ++k) {
    const std::size_t e = head.find('\n');
    head.remove_prefix(e == std::string_view::npos ? head.size() : e + 1);
  }
  if (given == Dialect::kAuto) {
    std::string tail;  // a last line without '\n' at the end of the file is looked at too
    std::string_view lines = head;
    if (eof_ && !head.empty() && head.back() != '\n') {
      tail.assign(head);
      tail += '\n';
      lines = tail;
    }
    report_.dialect = detect_dialect(lines, leader_left_ + 1);
  } else {
    report_.dialect.dialect = given;
  }
  interp_.set_dialect(report_.dialect.dialect);
  fanuc_ = report_.dialect.dialect == Dialect::kFanuc;
  if (!fanuc_) {
    // LinuxCNC has no tape leader: only blank lines may come before the
    // opening '%' (rs274 reads any other line as a block and then refuses
    // the '%': "Bad character '%' used"). The lines are read as the
    // program; a '%' after them is refused where it stands (next()).
    leader_left_ = report_.leader_lines = 0;
    return;
  }
  // A macro statement in the head (the first 64 KiB, where a macro
  // program's text usually is whole): flattened from the first block on.
  while (!head.empty() && !flatten_from_start_) {
    const std::size_t e = head.find('\n');
    flatten_from_start_ = fanuc_needs_flattening(head.substr(0, e));
    head.remove_prefix(e == std::string_view::npos ? head.size() : e + 1);
  }
}

void ProgramReader::start_flattening(std::string_view first, bool newline) {
  // The rest of the program in memory: loops and calls go back and forth.
  std::string data(first);
  if (newline) data += '\n';
  data.append(buf_.data() + begin_, end_ - begin_);
  begin_ = end_;
  while (!eof_) {
    const std::size_t at = data.size();
    data.resize(at + (std::size_t{1} << 20));
    in_.read(data.data() + at, static_cast<std::streamsize>(std::size_t{1} << 20));
    data.resize(at + static_cast<std::size_t>(in_.gcount()));
    if (in_.gcount() == 0) eof_ = true;
  }
  original_rest_ = data;
  // Its lines beyond the first (counted by physical() already).
  flattened_extra_lines_ = static_cast<long>(std::count(data.begin(), data.end(), '\n')) +
                           (!data.empty() && data.back() != '\n' ? 1 : 0) - 1;
  // What follows a closing '%' is not run: set aside, handed out verbatim.
  if (opened_) {
    std::size_t b = first.size() + (newline ? 1 : 0);  // (the first line is not a '%' line)
    while (b < data.size()) {
      std::size_t e = data.find('\n', b);
      e = e == std::string::npos ? data.size() : e + 1;
      if (is_percent_line(std::string_view(data).substr(b, e - b))) {
        // The closing '%' with it: the flat program may end earlier (at
        // M2), and the tape still ends with its '%'.
        const auto newlines =
            std::count(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(b), '\n');
        trailer_ =
            flatten::make_source(file_, data.substr(b), number_ + static_cast<int>(newlines));
        report_.trailer_lines = static_cast<int>(trailer_->size()) - 1;
        data.resize(b);
        break;
      }
      b = e;
    }
  }
  report_.flattened_from = number_;
  params_ = std::make_unique<flatten::Parameters>(interp_);
  for (const auto& [n, v] : interp_.setup().parameters) params_->load(n, v);
  flat_ = std::make_unique<flatten::Flattener>(*params_, path_);
  if (fanuc_) {
    fanuc_variables_ = std::make_unique<flatten::FanucVariables>();
    for (const auto& [n, v] : interp_.setup().parameters) fanuc_variables_->load(n, v);
    flat_->set_fanuc(fanuc_variables_.get(), flatten_from_start_);
  }
  flat_->set_max_executed_lines(max_executed_);
  auto source = flatten::make_source(file_, std::move(data), number_);
  report_.flat_source_lines = static_cast<long>(source->size());
  flat_->start(std::move(source));
}

void ProgramReader::linuxcnc_percent_line(std::string_view text, int line) const {
  // rs274 (interp_read.cc, read_text): a '%' line is '%' alone (spaces
  // around it); it opens the program only as the first line that is not
  // blank, and closes it after that. Anything else is "Bad character '%'".
  const std::string_view t = trimmed(flatten::without_cr(text));
  if (t != "%")
    throw InputError(file_, line,
                     "'%' with text after it: LinuxCNC refuses it (\"Bad character '%' used\"); "
                     "a program delimiter is '%' alone on its line");
  if (!opened_ && content_seen_ && !interp_.state().ended)
    throw InputError(file_, line,
                     "'%' after the program began: LinuxCNC refuses it (\"Bad character '%' "
                     "used\"); it opens a program only as its first line that is not blank. "
                     "Put a '%' line first (the program then ends at this one), or remove this "
                     "one (a Fanuc tape's leader before '%': --dialect fanuc)");
}

void ProgramReader::linuxcnc_end_of_file() const {
  if (fanuc_ || !opened_ || closed_ || interp_.state().ended) return;
  throw InputError(file_, number_,
                   "the program opens with '%' and ends without a closing '%' (or M2/M30): "
                   "LinuxCNC refuses it (\"File ended with no percent sign\"); add a '%' line "
                   "at the end");
}

bool ProgramReader::next(ProgramLine& out) {
  if (!started_) {
    started_ = true;
    find_leader();
    choose_dialect();
    if (report_.byte_order_mark) {
      out = ProgramLine{kByteOrderMark, &file_, 1, false, true, false, false, false, {}};
      return true;
    }
  }
  if (flat_) {
    flatten::FlatLine f;
    if (!flat_->next(f, interp_.state().ended)) {
      report_.flat_blocks = flat_->emitted_lines();
      if (!trailer_) linuxcnc_end_of_file();
      if (!trailer_ || trailer_next_ >= trailer_->size()) return false;
      const std::size_t k = trailer_next_++;
      out = ProgramLine{trailer_->line(k),
                        &file_,
                        trailer_->first_line + static_cast<int>(k),
                        trailer_->newline[k],
                        k > 0,
                        false,
                        false,
                        true,
                        {}};
      return true;
    }
    report_.flat_blocks = flat_->emitted_lines();
    // (A flattened program's closing '%' is in trailer_: one here is in
    // the middle of the program.)
    if (!fanuc_ && !f.verbatim && f.file && *f.file == file_ && is_percent_line(f.text))
      linuxcnc_percent_line(f.text, f.line);
    out = ProgramLine{f.text, f.file, f.line, f.newline, f.verbatim, f.rewritten, true, false, {}};
    return true;
  }
  std::string_view text;
  bool newline = false;
  if (!physical(text, newline)) {
    linuxcnc_end_of_file();
    return false;
  }
  out.text = text;
  out.file = &file_;
  out.line = number_;
  out.newline = newline;
  out.verbatim = out.rewritten = out.plain = out.flattened = false;
  if (leader_left_ > 0) {
    --leader_left_;
    out.verbatim = true;
    return true;
  }
  if (closed_) {
    ++report_.trailer_lines;
    out.verbatim = true;
    return true;
  }
  // The usual line: axis words only (read here once, for the post), or no
  // character that could make it more than literal words.
  // (Fanuc: a number without a point means another thing; the interpreter
  // reads every block.)
  if (!fanuc_ && lex_plain_axis_words(flatten::without_cr(text), out.words)) {
    out.plain = true;
    content_seen_ = true;
    return true;
  }
  if (!fanuc_ && !maybe_special(text)) {
    content_seen_ = content_seen_ || !trimmed(flatten::without_cr(text)).empty();
    return true;
  }
  if (fanuc_ && is_program_number_line(text)) {
    // O1001 / :1001: the program's number, which the control stores it
    // under; nothing to run.
    out.verbatim = true;
    return true;
  }
  if (is_percent_line(text)) {
    if (!fanuc_) linuxcnc_percent_line(text, number_);
    if (opened_) closed_ = true;
    opened_ = true;
    return true;
  }
  if (!fanuc_ && !content_seen_ && !trimmed(flatten::without_cr(text)).empty())
    content_seen_ = true;
  const bool flatten =
      fanuc_ ? flatten_from_start_ || fanuc_needs_flattening(text) : needs_flattening(text);
  if (flatten && !interp_.state().ended) {
    start_flattening(text, newline);
    return next(out);
  }
  return true;
}

}  // namespace volmap::nc
