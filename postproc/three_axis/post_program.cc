// post_program: the program read line by line through ProgramPost
// (program_post.h), the output flushed also on failure.
#include "postproc/three_axis/post_program.h"

#include <cmath>
#include <istream>
#include <ostream>
#include <stdexcept>

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
  nc::ProgramReader reader(in, in_name, post.interpreter(), options.subroutine_path);
  nc::ProgramLine l;
  try {
    while (reader.next(l)) post.line(l);
  } catch (const std::out_of_range& e) {
    // An error table's range (the message names the table's file:line):
    // the block that left it is the program's line (docs/model.md).
    post.flush();
    throw InputError(l.file ? *l.file : in_name, l.line,
                     std::string("this block leaves the error tables: ") + e.what() +
                         " (`post.clamp` holds the end values)");
  } catch (...) {
    post.flush();
    throw;
  }
  post.finish(reader.original_rest());
  PostReport report = post.report();
  report.read = reader.report();
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
