// post_program: the program read line by line through ProgramPost
// (program_post.h), the output flushed also on failure; a flattened part
// held back while it changes nothing, and the changed lines recorded.
#include "postproc/three_axis/post_program.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string_view>

#include "core/common/input_error.h"
#include "core/common/internal_error.h"
#include "maps/tables/volumetric_table.h"
#include "postproc/three_axis/corrector.h"
#include "postproc/three_axis/program_post.h"

namespace volmap::post {

void ProgramPost::finish(const std::string& original_rest) {
  // (A flattened part that ran as no block, such as a file of subroutine
  // definitions only, changed nothing either.)
  if (holding_ || (!hold_begun_ && !original_rest.empty())) {
    report_.lines_out -= static_cast<std::uint64_t>(
        std::count(out_buffer_.data(), out_buffer_.data() + out_buffer_.size(), '\n'));
    out_buffer_.clear();
    report_.lines_out +=
        static_cast<std::uint64_t>(std::count(original_rest.begin(), original_rest.end(), '\n'));
    write_out(original_rest.data(), original_rest.size());
    report_.flattened_written_as_read = true;
    holding_ = false;
  }
  flush();
  if (last_byte_ != '\n' && last_byte_ != 0) ++report_.lines_out;  // a last line without '\n'
  if (self_check_) {
    report_.self_checked = true;
    report_.self_check = self_check_->stats();
  }
}

void ProgramPost::line(const nc::ProgramLine& l) {
  if (l.flattened && !hold_begun_) begin_hold();
  const bool record = report_.changes.size() < options_.max_recorded_changes;
  // The line's output stays in the buffer, from `before` on, until the
  // line is done: add_decimal_points, check_held_line, the self-check and
  // record_change read it there (a flush inside the line made
  // `size() - before` wrap).
  keep_line_ = true;
  const std::size_t before = out_buffer_.size();
  if (l.verbatim) {
    ++report_.lines;
    line_ending_[0] = '\n';
    line_ending_size_ = l.newline ? 1 : 0;
    emit(l.text);
  } else {
    line_file_ = l.file ? l.file : &file_;
    evaluated_ = l.rewritten;
    line(l.text, l.line, l.newline, l.plain ? &l.words : nullptr);
    if (interp_.fanuc()) add_decimal_points(l, before);
  }
  if (holding_) check_held_line(l, before);
  if (self_check_) {
    const std::string_view out(out_buffer_.data() + before, out_buffer_.size() - before);
    if (l.verbatim)
      self_check_->skipped(out);
    else
      self_check_->written(out, corrector(), l.file ? *l.file : file_, l.line);
  }
  if (record) record_change(l, before);
  keep_line_ = false;
  if (out_buffer_.size() >= kFlushAt && !holding_) flush();
}

// The flattened part is held back while each of its lines comes out as it
// went in (finish() may then write the program as read instead).
void ProgramPost::check_held_line(const nc::ProgramLine& l, std::size_t before) {
  const std::size_t n = out_buffer_.size() - before;
  const std::size_t want = l.text.size() + (l.newline ? 1 : 0);
  if (n == want && std::memcmp(out_buffer_.data() + before, l.text.data(), l.text.size()) == 0 &&
      (!l.newline || out_buffer_.data()[before + n - 1] == '\n'))
    return;
  holding_ = false;
}

void ProgramPost::add_decimal_points(const nc::ProgramLine& l, std::size_t before) {
  const std::string_view out(out_buffer_.data() + before, out_buffer_.size() - before);
  if (out.substr(0, l.text.size()) == l.text) return;  // as read (its ending after it)
  std::string fixed;
  fixed.reserve(out.size() + 8);
  char close = 0;
  for (std::size_t i = 0; i < out.size();) {
    const char c = out[i];
    fixed += c;
    ++i;
    if (close) {
      if (c == close) close = 0;
      continue;
    }
    if (c == '(') {
      close = ')';
      continue;
    }
    if (c == ';') close = '\n';
    if (!std::strchr("XYZABCIJKRQxyzabcijkrq", c) || c == '\0') continue;
    std::size_t k = i;
    if (k < out.size() && (out[k] == '-' || out[k] == '+')) ++k;
    bool nonzero = false;
    const std::size_t digits = k;
    while (k < out.size() && out[k] >= '0' && out[k] <= '9') nonzero |= out[k++] != '0';
    if (k == digits || (k < out.size() && out[k] == '.')) continue;
    fixed.append(out.substr(i, k - i));
    if (nonzero) fixed += '.';
    i = k;
  }
  if (fixed.size() == out.size()) return;
  out_buffer_.commit(out_buffer_.data() + before);
  out_buffer_.append(fixed);
}

// --report's changed lines: the line as read and what was written for it.
void ProgramPost::record_change(const nc::ProgramLine& l, std::size_t before) {
  std::string_view out(out_buffer_.data() + before, out_buffer_.size() - before);
  const std::string_view in = l.text;
  if (out.size() == in.size() + (l.newline ? 1 : 0) && out.substr(0, in.size()) == in) return;
  if (!out.empty() && out.back() == '\n') out.remove_suffix(1);
  report_.changes.push_back({l.file && l.file != &file_ ? *l.file : std::string(), l.line,
                             std::string(nc::flatten::without_cr(in)), std::string(out)});
}

namespace {
// A program that moves nothing: empty, or every line leader, trailer,
// comment or a code without motion. Its output would be its input; most
// likely it is not the program that was meant (a leader that swallowed it,
// the wrong file), so it is refused with what was read.
[[noreturn]] void refuse_motion_free(const std::string& in_name, const nc::ProgramReader& reader) {
  const nc::ReadReport& r = reader.report();
  const long lines = reader.input_lines();
  std::string what = lines == 0 ? "the file is empty" : fmt::format("{} lines read", lines);
  if (r.leader_lines > 0)
    what += fmt::format(", {} of them tape leader before the '%' on line {}", r.leader_lines,
                        r.leader_lines + 1);
  if (r.trailer_lines > 0) what += fmt::format(", {} after the closing '%'", r.trailer_lines);
  // (At the '%' that ended a leader, else where the reading ended.)
  const int at = r.leader_lines > 0 ? r.leader_lines + 1 : static_cast<int>(std::max(1L, lines));
  throw InputError(in_name, at,
                   what +
                       "; no block moves the machine, so there is nothing to post: check that "
                       "this is the program meant");
}

PostReport run_post(std::istream& in, const std::string& in_name, std::ostream& out,
                    const Machine& machine, const ErrorSet& errors,
                    const maps::VolumetricTable* table, const nc::ProgramSetup& setup,
                    const PostOptions& options) {
  if (!(options.tolerance_mm > 0) || !std::isfinite(options.tolerance_mm))
    throw std::invalid_argument("`tolerance_um` must be a positive finite number");
  if (table)
    Corrector check(machine, *table, options.outside);  // a wrong table fails before any output
  ProgramPost post(in_name, out, machine, errors, setup, options, table);
  nc::ProgramReader reader(in, in_name, post.interpreter(), options.subroutine_path);
  reader.set_max_executed_lines(options.max_executed_lines);
  nc::ProgramLine l;
  bool reading = true;  // in the reader (the line after l), else posting l
  try {
    while ((reading = true, reader.next(l))) {
      reading = false;
      post.line(l);
    }
  } catch (const OutsideTable& e) {
    // An error table's range (the message names the table's file:line):
    // the block that left it is the program's line (docs/model.md).
    post.flush();
    throw InputError(l.file ? *l.file : in_name, l.line,
                     std::string("this block leaves the error tables: ") + e.what() +
                         " (`post.clamp` holds the end values)");
  } catch (const std::exception& e) {
    post.flush();
    // A bug, not the input's fault: said so, at the line it happened on.
    if (reading)
      throw_if_unexpected(e, in_name, static_cast<int>(reader.input_lines()));
    else
      throw_if_unexpected(e, l.file ? *l.file : in_name, l.line);
    throw;
  } catch (...) {
    post.flush();
    throw;
  }
  if (post.report().moves == 0) refuse_motion_free(in_name, reader);
  post.finish(reader.original_rest());
  PostReport report = post.report();
  report.read = reader.report();
  report.lines_in = static_cast<std::uint64_t>(reader.input_lines());
  return report;
}

}  // namespace

PostReport post_program(std::istream& in, const std::string& in_name, std::ostream& out,
                        const Machine& machine, const ErrorSet& errors,
                        const nc::ProgramSetup& setup, const PostOptions& options) {
  return run_post(in, in_name, out, machine, errors, nullptr, setup, options);
}

PostReport post_program(std::istream& in, const std::string& in_name, std::ostream& out,
                        const Machine& machine, const maps::VolumetricTable& table,
                        const nc::ProgramSetup& setup, const PostOptions& options) {
  static const ErrorSet kNoErrors;
  return run_post(in, in_name, out, machine, kNoErrors, &table, setup, options);
}

}  // namespace volmap::post
