// post_program: the program read line by line through ProgramPost
// (program_post.h), the output flushed also on failure.
#include "postproc/three_axis/post_program.h"

#include <cmath>
#include <cstring>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/common/input_error.h"
#include "maps/tables/volumetric_table.h"
#include "postproc/three_axis/corrector.h"
#include "postproc/three_axis/program_post.h"

namespace volmap::post {
namespace {
PostReport run_post(std::istream& in, const std::string& in_name, std::ostream& out,
                    const Machine& machine, const ErrorSet& errors,
                    const maps::VolumetricTable* table, const nc::ProgramSetup& setup,
                    const PostOptions& options) {
  if (!(options.tolerance_mm > 0) || !std::isfinite(options.tolerance_mm))
    throw std::invalid_argument("`tolerance_um` must be a positive finite number");
  if (table)
    Corrector check(machine, *table, options.outside);  // a wrong table fails before any output
  ProgramPost post(in_name, out, machine, errors, setup, options, table);
  // Lines out of a large buffer (getline's per-line work and copies avoided);
  // the buffer grows only to hold the longest line.
  std::vector<char> buf(1 << 16);
  std::size_t begin = 0, end = 0;
  bool eof = false;
  int number = 0;
  try {
    for (;;) {
      const char* nl = static_cast<const char*>(std::memchr(buf.data() + begin, '\n', end - begin));
      if (nl) {
        const auto at = static_cast<std::size_t>(nl - buf.data());
        post.line(std::string_view(buf.data() + begin, at - begin), ++number, true);
        begin = at + 1;
        continue;
      }
      if (eof) {
        if (begin < end)
          post.line(std::string_view(buf.data() + begin, end - begin), ++number, false);
        break;
      }
      const std::size_t rest = end - begin;
      std::memmove(buf.data(), buf.data() + begin, rest);
      begin = 0;
      end = rest;
      if (end == buf.size()) buf.resize(2 * buf.size());
      in.read(buf.data() + end, static_cast<std::streamsize>(buf.size() - end));
      const auto got = static_cast<std::size_t>(in.gcount());
      end += got;
      if (got == 0) eof = true;
    }
  } catch (const std::out_of_range& e) {
    // An error table's range (the message names the table's file:line):
    // the block that left it is the program's line (docs/model.md).
    post.flush();
    throw InputError(in_name, number,
                     std::string("this block leaves the error tables: ") + e.what() +
                         " (`post.clamp` holds the end values)");
  } catch (...) {
    post.flush();
    throw;
  }
  post.flush();
  return post.report();
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
