// What each libFuzzer target does with one input (tests/fuzz/*_fuzz.cc),
// shared with tests/fuzz_regressions_test.cc, which replays the seed
// corpora and every input a fuzzer has found (tests/fuzz/regressions/) in
// the ordinary test suite (and so under the sanitizers of .ci/run).
//
// The only acceptable failure of a reader is volmap::InputError; any other
// exception escapes (a bug: its message would not name file and line), and a
// non-finite number in what was read calls std::abort (it would reach an
// output).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <string_view>

#include "core/common/input_error.h"
#include "core/measure/recordings.h"
#include "core/model/errors_csv.h"
#include "core/model/errors_import.h"
#include "core/model/location_convention.h"
#include "core/model/machine_json.h"
#include "gcode/nc_block.h"
#include "gcode/nc_interpreter.h"
#include "gcode/program_reader.h"
#include "postproc/five_axis/five_axis_input.h"
#include "postproc/three_axis/post_program.h"

namespace volmap::fuzz {

inline void require(bool ok) {
  if (!ok) std::abort();
}

/// The NC reader: lexing and interpretation line by line, as volmap post
/// and verify read a program, with and without a known initial position,
/// as LinuxCNC and as Fanuc (--dialect fanuc) read it.
inline void nc_reader(std::string_view program) {
  for (int run = 0; run < 4; ++run) {
    const bool initial = run & 1;
    nc::ProgramSetup setup;
    setup.dialect = run & 2 ? nc::Dialect::kFanuc : nc::Dialect::kLinuxCnc;
    setup.work_offset_mm[0] = Eigen::Vector3d(250, 200, 100);
    setup.work_offset_mm[1] = Eigen::Vector3d(-10, 5, 0);
    setup.tool_length_mm[1] = 50.0;
    setup.tool_length_mm[2] = 120.5;
    setup.tool_diameter_mm[1] = 6.0;  // cutter compensation (G41 D1, D2: the side swapped)
    setup.tool_diameter_mm[2] = -4.0;
    if (initial) setup.initial_position_mm = Eigen::Vector3d(0, 0, 300);
    nc::Interpreter interp(setup, "fuzz.ngc");
    nc::BlockEffect fx;
    int number = 0;
    size_t pos = 0;
    try {
      while (pos <= program.size()) {
        size_t eol = program.find('\n', pos);
        if (eol == std::string_view::npos) eol = program.size();
        std::string_view text = program.substr(pos, eol - pos);
        if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
        const nc::Block b = nc::lex_block(text, ++number, "fuzz.ngc");
        // The post's shortcut reads a plain line's words as the lexer does.
        nc::PlainAxisWords plain;
        if (nc::lex_plain_axis_words(text, plain)) {
          const std::size_t g1 = plain.g1 ? 1 : 0;  // a leading G1 word
          require(b.words.size() == static_cast<std::size_t>(plain.count) + g1);
          if (g1) require(b.words[0].letter == 'G' && b.words[0].code10 == 10);
          for (std::size_t k = g1; k < b.words.size(); ++k) {
            const nc::Word& w = b.words[k];
            require(w.letter >= 'X' && w.letter <= 'Z' && (plain.given >> (w.letter - 'X') & 1u) &&
                    std::memcmp(&w.value, &plain.value[w.letter - 'X'], sizeof(double)) == 0);
          }
        }
        interp.execute(b, fx);
        if (fx.has_motion) {
          const nc::Motion& m = fx.motion;
          require(m.start_mm.allFinite() && m.end_mm.allFinite() && m.center_mm.allFinite() &&
                  std::isfinite(m.r_mm) && std::isfinite(m.clear_mm) && std::isfinite(m.feed));
        }
        require(interp.state().position_mm.allFinite());
        pos = eol + 1;
      }
    } catch (const InputError&) {
    }
  }
}

/// volmap post (three axes) on the sample machine and its errors: the first
/// byte chooses the options (bit 0 --keep-arcs, 1 --expand-cycles, 2 the
/// tolerance, 3 decimals, 4 and 5 the dialect: auto, fanuc, linuxcnc,
/// fanuc; 6 G28's and G30's positions #5161.. and #5181.. given, as a
/// --var-file gives them), the rest is the program, of which the first 16
/// lines are posted (arcs of up to 65 536 pieces each stay well inside the
/// time limit). The program is posted with and without the shortcut of
/// plain lines: both must refuse it with the same InputError or write the
/// same bytes and count the same. Cutters for G41/G42 D1 and D2 (Fanuc:
/// the D offset number reads tool n's row).
// Programs with parameters, expressions and O-word control flow: the
// program reader flattens them into the interpreter (a bounded number of
// executed lines: an endless loop is refused, not waited for).
inline void nc_flatten_as(std::string_view program, nc::Dialect dialect) {
  nc::ProgramSetup setup;
  setup.dialect = dialect;
  setup.work_offset_mm[0] = Eigen::Vector3d(250, 200, 100);
  setup.initial_position_mm = Eigen::Vector3d(250, 200, 300);
  setup.tool_length_mm[1] = 50.0;
  setup.tool_diameter_mm[1] = 6.0;
  nc::Interpreter interp(setup, "fuzz.ngc");
  std::istringstream in{std::string(program)};
  nc::ProgramReader reader(in, "fuzz.ngc", interp, {});
  reader.set_max_executed_lines(20000);
  nc::ProgramLine l;
  nc::Block b;
  nc::BlockEffect fx;
  try {
    while (reader.next(l)) {
      if (l.verbatim) continue;
      std::string_view text = l.text;
      if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
      nc::lex_block_into(text, l.line, *l.file, b);
      b.evaluated = l.rewritten;
      interp.execute(b, fx);
      if (fx.has_motion) require(fx.motion.end_mm.allFinite());
    }
  } catch (const InputError&) {
  }
}

// As the program's head says (--dialect auto), then as Fanuc Custom Macro B.
inline void nc_flatten(std::string_view program) {
  nc_flatten_as(program, nc::Dialect::kAuto);
  nc_flatten_as(program, nc::Dialect::kFanuc);
}
// The same read as Fanuc Custom Macro B (--dialect fanuc).
inline void nc_fanuc(std::string_view program) { nc_flatten_as(program, nc::Dialect::kFanuc); }

inline void post(std::string_view input) {
  if (input.empty()) return;
  static const Machine machine =
      load_machine_json(std::string(VOLMAP_SOURCE_DIR) + "/samples/machines/hsu-3axis.json");
  static const ErrorSet errors =
      load_errors_csv(std::string(VOLMAP_SOURCE_DIR) + "/samples/errors/hsu-3axis.csv");
  const auto options = static_cast<unsigned char>(input[0]);
  std::string_view program = input.substr(1);
  size_t cut = 0;
  for (int line = 0; line < 16 && cut != std::string_view::npos; ++line) {
    cut = program.find('\n', cut);
    if (cut != std::string_view::npos) ++cut;
  }
  if (cut != std::string_view::npos) program = program.substr(0, cut);
  nc::ProgramSetup setup;
  setup.work_offset_mm[0] = Eigen::Vector3d(250, 200, 100);
  setup.tool_length_mm[1] = 12.5;
  // Cutters small enough that compensation is kept at 1 um on the sample
  // (2 r L = 0.12 um), the second with its side swapped.
  setup.tool_diameter_mm[1] = 0.2;
  setup.tool_diameter_mm[2] = -0.1;
  setup.initial_position_mm = Eigen::Vector3d(250, 200, 150);
  static constexpr nc::Dialect kDialects[] = {nc::Dialect::kAuto, nc::Dialect::kFanuc,
                                              nc::Dialect::kLinuxCnc, nc::Dialect::kFanuc};
  setup.dialect = kDialects[(options >> 4) & 3u];
  if (options & 64u) {
    // G28 and G30 positions (machine coordinates, inside the travel).
    for (int k = 0; k < 3; ++k) {
      setup.parameters[5161 + k] = std::array<double, 3>{100, 50, 280}[k];
      setup.parameters[5181 + k] = std::array<double, 3>{400, 350, 250}[k];
    }
  }
  std::string out[2], error[2];
  post::PostReport report[2];
  for (int k = 0; k < 2; ++k) {
    post::PostOptions o;
    o.max_executed_lines = 20000;  // an endless loop refused, not waited for
    o.keep_arcs = options & 1u;
    o.expand_cycles = options & 2u;
    o.tolerance_mm = (options & 4u) ? 5e-3 : 1e-3;
    o.decimals = (options & 8u) ? 6 : -1;
    o.shortcuts = k == 0;
    std::istringstream in{std::string(program)};
    std::ostringstream os;
    try {
      report[k] = post::post_program(in, "fuzz.ngc", os, machine, errors, setup, o);
    } catch (const InputError& e) {
      error[k] = e.what();
    }
    out[k] = os.str();
  }
  require(error[0] == error[1]);
  require(out[0] == out[1]);
  require(report[0].lines == report[1].lines &&
          report[0].lines_changed == report[1].lines_changed &&
          report[0].lines_added == report[1].lines_added &&
          report[0].points_corrected == report[1].points_corrected);
}

/// The recordings CSV reader, and the writer on what it read.
inline void recordings_csv(std::string_view text) {
  std::istringstream in{std::string(text)};
  try {
    const Recordings r = read_recordings_csv(in, "fuzz.csv");
    r.check_consistent();
    std::ostringstream out;
    write_recordings_csv(out, r);
  } catch (const InputError&) {
  }
}

/// The errors readers: errors.md CSV and, by format detection, ISG CSV and
/// the Etalon exchange format.
inline void errors_csv(std::string_view text) {
  static const Machine machine =
      load_machine_json(std::string(VOLMAP_SOURCE_DIR) + "/samples/machines/lei-hsu-xyzac.json");
  std::istringstream in{std::string(text)};
  ErrorSet errors;
  try {
    errors = read_errors(in, "fuzz.csv", ErrorsFormat::kAuto);
  } catch (const InputError&) {
    return;
  }
  // What was read converts between the location errors' meanings, or is
  // refused (an axis the machine lacks, errors too large to be small).
  for (LocationConvention to : {LocationConvention::kIso230, LocationConvention::kLink}) {
    try {
      const ConventionConversion r =
          convert_location_convention(machine, errors, to, Formulation::kIndependent);
      for (const auto& [name, value] : r.errors.location) require(std::isfinite(value));
    } catch (const std::invalid_argument&) {
    } catch (const std::out_of_range&) {
    }
  }
}

/// The machine definition reader, and the nominal forward transformation
/// in the middle of the travel of what it read.
inline void machine_json(std::string_view text) {
  std::istringstream in{std::string(text)};
  try {
    const Machine m = read_machine_json(in, "fuzz.json");
    AxisVector u(m.axis_count());
    for (int i = 0; i < m.axis_count(); ++i) {
      const AxisLimits& L = m.limits[static_cast<size_t>(i)];
      u[i] = L.unlimited ? 0.0 : 0.5 * L.min + 0.5 * L.max;
    }
    const ToolPose p = nominal_forward(m, u);
    require(p.tip_mm.allFinite() && p.axis.allFinite());
  } catch (const InputError&) {
  }
}

/// The APT / CLDATA reader (five-axis post), on the five-axis sample
/// machine: every line and move to the end, or an InputError.
inline void apt_reader(std::string_view text) {
  static const Machine machine =
      load_machine_json(std::string(VOLMAP_SOURCE_DIR) + "/samples/machines/lei-hsu-xyzac.json");
  std::istringstream in{std::string(text)};
  try {
    post::FiveAxisReader reader(in, "fuzz.apt", machine, post::InputForm::kApt, post::InitialPose{},
                                1e-3);
    post::FiveAxisLine l;
    int moves = 0;
    while (reader.next(l) && moves < 100000) {
      if (!l.has_move) continue;
      ++moves;
      const nc::Motion& m = l.move.tip;
      require(m.start_mm.allFinite() && m.end_mm.allFinite() && m.center_mm.allFinite() &&
              l.move.a1.allFinite() && std::isfinite(l.move.feed));
    }
  } catch (const InputError&) {
  }
}

}  // namespace volmap::fuzz
