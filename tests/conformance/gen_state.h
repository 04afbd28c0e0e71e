// The generator's internals (generator.h): what the controller's state is
// after the lines written so far, and the writers of words and moves that
// keep it. Positions are the tip's, relative to the G54 origin, in mm (w);
// the program's coordinates are w minus the frame shift (G52/G92, G55).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "tests/conformance/generator.h"

namespace volmap::conformance::gen {

using Vec = Eigen::Vector3d;

/// How a program spells its words (one choice per program).
struct Style {
  int decimals_mm = 4, decimals_inch = 4;
  bool strip_zeros = true;  ///< "10.5" rather than "10.5000"
  bool lower = false;       ///< "g1 x10"
  bool compact = false;     ///< "G1X10Y5"
  bool line_numbers = false;
  bool restate_motion = true;  ///< every move names its G code
};

class Gen {
 public:
  explicit Gen(std::uint64_t seed);

  // Randomness.
  double uniform(double lo, double hi);
  int integer(int lo, int hi);
  bool chance(double p);
  template <typename T>
  const T& pick(const std::vector<T>& v) {
    return v[static_cast<size_t>(integer(0, static_cast<int>(v.size()) - 1))];
  }

  // State.
  bool inch = false;
  bool incremental = false;     ///< G91
  bool arc_absolute = false;    ///< G90.1
  int plane = 0;                ///< 0 G17, 1 G18, 2 G19
  Vec w = Vec::Zero();          ///< tip, relative to the G54 origin (mm)
  Vec shift = Vec::Zero();      ///< program coordinates = w - shift (G52/G92/G55)
  Vec cs_shift = Vec::Zero();   ///< the coordinate system's origin - G54's (G55, G10)
  Vec g92_shift = Vec::Zero();  ///< the G92/G52 offset (mm)
  void update_shift() { shift = cs_shift + g92_shift; }
  bool retract_r = true;     ///< G99 (the interpreter's start) or G98
  bool known = false;        ///< X, Y and Z have been commanded
  double tool_offset = 0.0;  ///< G43 length offset in effect (mm)
  int tool = 0;              ///< the tool in the spindle (M6)
  int spindle = 0;           ///< 3 M3, 4 M4, 0 stopped
  bool feed_set = false;
  bool comp = false;  ///< G41/G42 on
  int motion = 0;     ///< modal motion (0, 1, 2, 3, 80 none/cycle)
  bool user_m = false;
  int label = 100;  ///< next O-word number
  Style style;
  /// The region the part lies in (w, mm): moves stay inside it.
  Vec lo = Vec(-100, -80, -25), hi = Vec(100, 80, 50);
  double safe_z = 10;  ///< w, mm

  double unit() const { return inch ? 25.4 : 1.0; }
  Vec program(const Vec& w_mm) const { return w_mm - shift; }

  // Writing.
  std::vector<std::string> lines;  ///< the main program, without line ends
  std::vector<std::pair<std::string, std::string>> files;
  std::vector<std::string> features;
  void emit(const std::string& line);
  void feature(const std::string& name);
  /// A number in program units (value in units) at the style's decimals.
  std::string num(double value_units, int decimals = -1) const;
  /// A word: letter + number, in the style's case.
  std::string word(char letter, double value_units, int decimals = -1) const;
  std::string code(const std::string& c) const;  ///< "G1" in the style's case
  std::string join(const std::vector<std::string>& words) const;
  int decimals() const { return inch ? style.decimals_inch : style.decimals_mm; }
  /// The value a word written at `decimals` reads as (units).
  double rounded(double value_units, int decimals = -1) const;

  /// A straight move (G0 or G1) to the target (w, mm); axes not given keep
  /// theirs. Writes absolute or incremental words as the state says and
  /// updates w from the written numbers. `extra`: words appended.
  void move(int g, std::optional<double> x, std::optional<double> y, std::optional<double> z,
            const std::string& extra = "");
  void move_to(int g, const Vec& target, const std::string& extra = "") {
    move(g, target.x(), target.y(), target.z(), extra);
  }
  /// An arc in the current plane about centre c (w, mm) to the end (w, mm),
  /// with extra turns; r_form: R instead of the centre words.
  void arc(bool cw, const Vec& center, const Vec& end, int turns, bool r_form);
  /// The feed word when none is set yet ("" otherwise).
  std::string feed_word();
  /// A random point of the region (w).
  Vec random_point();
  Vec clamp(const Vec& p) const { return p.cwiseMax(lo).cwiseMin(hi); }
  void retract();  ///< G0 to the safe height
  void set_absolute();
  void set_plane(int p);
  void set_units(bool to_inch);

 private:
  std::mt19937_64 rng_;
};

/// Down to `depth` at (x, y): G90, up to the safe height, G0 over it, G1 down.
void approach(Gen& g, double x, double y, double depth);
/// A move's length: short, medium or long (mm).
double step_length(Gen& g);

// The features (gen_motion.cc, gen_setup.cc, gen_control.cc).
void lines_feature(Gen& g);
void zigzag_feature(Gen& g);
void contour_feature(Gen& g);
void circle_feature(Gen& g);
void plane_arc_feature(Gen& g);
void polar_feature(Gen& g);
void polar_spiral_feature(Gen& g);
void drill_feature(Gen& g);
void incremental_feature(Gen& g);
void units_feature(Gen& g);
void arc_distance_feature(Gen& g);
void local_offset_feature(Gen& g);
void g92_feature(Gen& g);
void g10_feature(Gen& g);
void home_feature(Gen& g);
void tool_change_feature(Gen& g);
void cutter_comp_feature(Gen& g);
void misc_feature(Gen& g);
void invalid_feature(Gen& g);
void g53_feature(Gen& g);
void sub_feature(Gen& g);
void loop_feature(Gen& g);
void if_feature(Gen& g);
void params_feature(Gen& g);
void user_m_feature(Gen& g);
void odd_feature(Gen& g);

}  // namespace volmap::conformance::gen
