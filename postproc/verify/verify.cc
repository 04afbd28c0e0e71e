#include "postproc/verify/verify.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <istream>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/common/input_error.h"
#include "core/common/internal_error.h"
#include "gcode/nc_path.h"
#include "gcode/program_reader.h"
#include "postproc/three_axis/corrector.h"

namespace volmap::post {
namespace {

using Eigen::Vector3d;

struct FeedMove {
  nc::Motion motion;  ///< cycles reduced to their feed-in: R plane to bottom
  double tool_length_mm;
  int line;
  bool measured;  ///< false for rapids: they move the axes (and take up
                  ///< lost motion) but are not cutting
};

// Where a program's cutter compensation begins: its side (1 G41, 2 G42),
// radius (mm) and line.
struct CompStart {
  int side;
  double radius_mm;
  int line;
};

// Refuses a compensated program whose compensation is not the nominal
// one's (verify measures programmed contours: the offsets must agree).
void check_same_compensation(const std::vector<CompStart>& nominal,
                             const std::vector<CompStart>& compensated,
                             const std::string& compensated_name) {
  for (size_t k = 0; k < std::max(nominal.size(), compensated.size()); ++k) {
    const bool same = k < nominal.size() && k < compensated.size() &&
                      nominal[k].side == compensated[k].side &&
                      std::abs(nominal[k].radius_mm - compensated[k].radius_mm) <= 1e-9;
    if (same) continue;
    auto what = [](const std::vector<CompStart>& v, size_t i) {
      return i < v.size() ? fmt::format("G4{} with radius {:g} mm (line {})", v[i].side,
                                        v[i].radius_mm, v[i].line)
                          : std::string("none");
    };
    throw InputError(compensated_name, k < compensated.size() ? compensated[k].line : 0,
                     fmt::format("cutter compensation {} differs from the nominal program's ({}): "
                                 "verify compares programmed contours, which the controller "
                                 "offsets; give the programs the same G41/G42 and tools",
                                 what(compensated, k), what(nominal, k)));
  }
}

// The feed moves of the lines `reader` gives (l: the line read last).
void feed_moves_of(nc::ProgramReader& reader, nc::Interpreter& interp, double default_tool_mm,
                   nc::ProgramLine& l, std::vector<FeedMove>& out, std::vector<CompStart>& comps) {
  nc::Block b;
  nc::BlockEffect fx;
  while (reader.next(l)) {
    if (l.verbatim) continue;
    const int number = l.line;
    std::string_view text = l.text;
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    nc::lex_block_into(text, number, *l.file, b);
    b.file = l.file == &reader.file() ? nullptr : l.file;
    b.evaluated = l.rewritten;
    interp.execute(b, fx);
    if (!fx.has_motion) continue;
    if (fx.comp_role == nc::CompRole::kEntry)
      comps.push_back({interp.state().comp_side, interp.state().comp_radius_mm, number});
    // The machine file's tool (offset zero) plus the active tool length offset.
    const double L = default_tool_mm + interp.state().tool_length_mm;
    nc::Motion m = fx.motion;
    if (m.kind == nc::MotionKind::kRapid) {
      // Before X, Y and Z are all known the start is a guess: skip.
      if (interp.state().position_known) out.push_back({m, L, number, false});
      continue;
    }
    if (m.kind == nc::MotionKind::kTap) {  // G33.1: in and back out, both cutting
      out.push_back({m, L, number, true});
      nc::Motion back = m;
      back.start_mm = m.end_mm;
      back.end_mm = m.start_mm;
      out.push_back({back, L, number, true});
      continue;
    }
    if (m.kind == nc::MotionKind::kCycle) {
      // Every hole (L repeats): rapid over it, down to R, then the feed to
      // the bottom and back to the clearance level.
      for (size_t k = 0; k <= fx.more_holes.size(); ++k) {
        nc::Motion h = k == 0 ? m : fx.more_holes[k - 1];
        nc::Motion over = h;
        over.kind = nc::MotionKind::kRapid;
        over.end_mm = Vector3d(h.end_mm.x(), h.end_mm.y(), h.r_mm);
        out.push_back({over, L, number, false});
        h.start_mm = over.end_mm;
        h.kind = nc::MotionKind::kLinear;
        out.push_back({h, L, number, true});
        nc::Motion back = h;
        back.kind = nc::MotionKind::kRapid;
        back.start_mm = h.end_mm;
        back.end_mm = Vector3d(h.end_mm.x(), h.end_mm.y(), h.clear_mm);
        out.push_back({back, L, number, false});
      }
      continue;
    }
    out.push_back({m, L, number, true});
  }
}

// Feed moves of a program, as the interpreter sees them.
std::vector<FeedMove> feed_moves(std::istream& in, const std::string& name,
                                 const nc::ProgramSetup& setup, double default_tool_mm,
                                 const std::vector<std::string>& subroutine_path,
                                 std::vector<CompStart>& comps) {
  nc::Interpreter interp(setup, name);
  nc::ProgramReader reader(in, name, interp, subroutine_path);
  std::vector<FeedMove> out;
  nc::ProgramLine l;
  try {
    feed_moves_of(reader, interp, default_tool_mm, l, out, comps);
  } catch (const std::exception& e) {
    throw_if_unexpected(e, l.file ? *l.file : name, l.line);  // a bug: said so, at its line
    throw;
  }
  return out;
}

class Run {
 public:
  Run(const Machine& machine, const ErrorSet& errors, OutsidePolicy outside)
      : machine_(machine), errors_(errors), outside_(outside) {}
  const Corrector& corrector(double L) {
    auto it = correctors_.find(L);
    if (it == correctors_.end())
      it =
          correctors_.emplace(L, std::make_unique<Corrector>(machine_, errors_, L, outside_)).first;
    return *it->second;
  }

 private:
  const Machine& machine_;
  const ErrorSet& errors_;
  OutsidePolicy outside_;
  std::map<double, std::unique_ptr<Corrector>> correctors_;
};

DeviationStats measure_moves(const std::vector<FeedMove>& commanded,
                             const std::vector<FeedMove>& nominal, Run& run, double step_mm,
                             const std::string& name, int& line, const VerifyOptions& options);

// As measure_moves; an error table left (OutsideTable from the model,
// naming the table) is reported at the program's line, and a move too long
// to sample is refused there.
DeviationStats measure(const std::vector<FeedMove>& commanded, const std::vector<FeedMove>& nominal,
                       Run& run, double step_mm, const std::string& name,
                       const VerifyOptions& options) {
  int line = 0;
  try {
    return measure_moves(commanded, nominal, run, step_mm, name, line, options);
  } catch (const OutsideTable& e) {
    throw InputError(name, line,
                     std::string("this block leaves the error tables: ") + e.what() +
                         " (`verify.clamp` holds the end values)");
  } catch (const std::exception& e) {
    throw_if_unexpected(e, name, line);  // a bug: said so, at its line
    throw;
  }
}

DeviationStats measure_moves(const std::vector<FeedMove>& commanded,
                             const std::vector<FeedMove>& nominal, Run& run, double step_mm,
                             const std::string& name, int& line, const VerifyOptions& options) {
  DeviationStats st;
  double sum2 = 0;
  size_t cursor = 0;
  // Lost motion as play: each axis's hysteresis state, -1 .. +1 (0: unknown
  // at the start, the mean of both directions).
  Vector3d h = Vector3d::Zero();
  Vector3d previous = commanded.empty() ? Vector3d::Zero() : commanded.front().motion.start_mm;
  double path_mm = 0.0;  // travel of the measured moves so far
  for (const FeedMove& fm : commanded) {
    if (options.progress)
      options.progress(name, static_cast<size_t>(&fm - commanded.data()), commanded.size());
    const Corrector& c = run.corrector(fm.tool_length_mm);
    const nc::Motion& m = fm.motion;
    line = fm.line;
    const double len = nc::path_length_mm(m);
    const double samples = std::ceil(len / step_mm);
    if (!(samples <= 1e8))  // also NaN: never cast to int out of range
      throw InputError(name, fm.line,
                       "this move is too long to sample (" + std::to_string(len) +
                           " mm); check its coordinates");
    const int n = std::max(8, static_cast<int>(samples));
    if (fm.measured) path_mm += len;
    for (int k = 0; k <= n; ++k) {
      const Vector3d x = nc::point_on(m, static_cast<double>(k) / n);
      c.take_up_play(previous, x, h);
      previous = x;
      if (!fm.measured) continue;
      const Vector3d actual = x + c.error_with_play(x, h);
      // Nearest nominal move around the cursor. The cursor follows the
      // nearest one, but a move beyond the next costs kSkipPenaltyMm per
      // move skipped: where the path crosses itself (a diagonal back over
      // the passes just cut) the cursor stays on the move being run, not
      // on the crossing one ahead, which would leave the window behind.
      constexpr double kSkipPenaltyMm = 0.05;
      double best = std::numeric_limits<double>::infinity();
      double best_score = best;
      size_t best_i = cursor;
      const size_t lo = cursor > 2 ? cursor - 2 : 0;
      const size_t hi = std::min(nominal.size(), cursor + 4);
      for (size_t i = lo; i < hi; ++i) {
        const double dist = nc::distance_to_path(nominal[i].motion, actual);
        best = std::min(best, dist);
        const double skipped = i > cursor + 1 ? static_cast<double>(i - cursor - 1) : 0.0;
        if (const double score = dist + kSkipPenaltyMm * skipped; score < best_score) {
          best_score = score;
          best_i = i;
        }
      }
      cursor = best_i;
      if (!std::isfinite(best)) continue;
      sum2 += best * best;
      ++st.samples;
      st.profile.add(path_mm - len + len * k / n, best * 1e3, 0.0, fm.line);
      if (best * 1e3 > st.max_um) {
        st.max_um = best * 1e3;
        st.worst_line = fm.line;
      }
    }
  }
  st.rms_um = st.samples ? std::sqrt(sum2 / static_cast<double>(st.samples)) * 1e3 : 0.0;
  return st;
}

}  // namespace

VerifyResult verify_programs(std::istream& nominal, const std::string& nominal_name,
                             std::istream& compensated, const std::string& compensated_name,
                             const Machine& machine, const ErrorSet& errors,
                             const nc::ProgramSetup& setup, const VerifyOptions& options) {
  VerifyResult r;
  std::vector<CompStart> nominal_comps, compensated_comps;
  const std::vector<FeedMove> nom = feed_moves(nominal, nominal_name, setup, machine.tool_length_mm,
                                               options.subroutine_path, nominal_comps);
  const std::vector<FeedMove> out =
      feed_moves(compensated, compensated_name, setup, machine.tool_length_mm,
                 options.subroutine_path, compensated_comps);
  check_same_compensation(nominal_comps, compensated_comps, compensated_name);
  // (Every compensated move follows an entry with its radius.)
  for (const CompStart& k : nominal_comps)
    r.comp_radius_mm = std::max(r.comp_radius_mm, k.radius_mm);
  Run run(machine, errors, options.outside);
  std::vector<FeedMove> nominal_path;
  for (const FeedMove& f : nom)
    if (f.measured) nominal_path.push_back(f);
  // A measurement of nothing is no success.
  if (nominal_path.empty())
    throw InputError(nominal_name, 0,
                     "no feed move to measure (G1, G2/G3, a canned cycle's feed-in): verify "
                     "measures the cutting moves, and this program has none; check that it is "
                     "the program meant");
  r.before = measure(nom, nominal_path, run, options.sample_step_mm, nominal_name, options);
  r.after = measure(out, nominal_path, run, options.sample_step_mm, compensated_name, options);
  if (r.after.samples == 0)
    throw InputError(compensated_name, 0,
                     "no feed move to measure, where the nominal program has some: check that "
                     "this is the program posted from it");
  return r;
}

}  // namespace volmap::post
