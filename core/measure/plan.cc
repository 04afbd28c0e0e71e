#include "core/measure/plan.h"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include "core/common/input_error.h"
#include "core/common/json_input.h"
#include "core/common/units.h"
#include "core/kinematics/kinematics.h"
#include "core/measure/circular_test.h"

namespace volmap {
namespace {

// Readings of one plan at most: beyond, a typo in a step would fill the
// memory (and a step count beyond long long is undefined behaviour).
constexpr double kMaxPlanPoints = 1e7;

constexpr double kStill = 1e-12;  // mm or rad: an axis that moved less did not move

std::string axis_key(AxisName a) { return std::string(1, axis_char(a)); }

double to_internal(AxisName a, double display) {
  return is_rotary(a) ? display * units::kRadPerDeg : display;
}

/// The values an axis (AxisVector index) takes in a test, in display
/// units (mm, degrees).
struct AxisValues {
  int index = 0;
  std::vector<double> values;
};

/// Steps `k` (one index per list) to the next combination of the lists'
/// values, the last list fastest; false after the last combination (k back
/// at all zeros).
bool next_combination(std::vector<std::size_t>& k, const std::vector<AxisValues>& lists) {
  for (std::size_t j = lists.size(); j-- > 0;) {
    if (++k[j] < lists[j].values.size()) return true;
    k[j] = 0;
  }
  return false;
}

class Expander {
 public:
  Expander(const std::string& file, const Machine& m) : file_(file), m_(m) {}

  Plan expand(const nlohmann::json& doc) {
    const JsonObject root(file_, doc, "");
    root.allow_only(
        {"format", "description", "seed", "noise_um", "frame", "temperature", "start", "tests"});
    if (root.has("format") && root.string("format") != "volmap-plan/1")
      root.fail("format", "expected \"volmap-plan/1\"");
    plan_.file = file_;
    if (root.has("seed")) {
      const double s = root.number("seed");
      if (s < 0 || s != std::floor(s) || s > 9.0e15)
        root.fail("seed", "expected a whole number >= 0");
      plan_.seed = static_cast<std::uint64_t>(s);
    }
    plan_.noise_um = root.number_or("noise_um", 0.0);
    if (plan_.noise_um < 0)
      root.fail("noise_um", "expected a number >= 0 (standard deviation in µm)");
    const std::string frame = root.string_or("frame", "workpiece");
    if (frame == "machine") {
      plan_.frame = RecordingFrame::kMachine;
    } else if (frame != "workpiece") {
      root.fail("frame", "expected \"workpiece\" or \"machine\"");
    }
    if (root.has("temperature")) {
      const JsonObject t = root.object("temperature");
      t.allow_only({"sensor", "start_c", "rise_c", "tau_s", "rate_c_per_h"});
      PlannedTemperature pt;
      pt.sensor = t.string("sensor");
      if (pt.sensor.empty() || pt.sensor.find_first_of(", \t") != std::string::npos)
        t.fail("sensor", "expected a sensor name without commas or spaces, e.g. \"x_screw\"");
      pt.start_c = t.number_or("start_c", 20.0);
      pt.rise_c = t.number_or("rise_c", 0.0);
      pt.tau_s = t.number_or("tau_s", 0.0);
      pt.rate_c_per_h = t.number_or("rate_c_per_h", 0.0);
      if (pt.tau_s < 0) t.fail("tau_s", "expected a number >= 0");
      plan_.temperature = pt;
    }
    cur_ = m_.home;
    if (root.has("start")) cur_ = positions_from(root.object("start"), m_.home);
    const std::vector<JsonObject> tests = root.objects("tests");
    if (tests.empty()) root.fail("tests", "expected at least one test");
    for (const JsonObject& t : tests) expand_test(t);
    return std::move(plan_);
  }

 private:
  /// An object of axis letters -> one value (mm, degrees); others from `base`.
  AxisVector positions_from(const JsonObject& o, const AxisVector& base) const {
    AxisVector u = base;
    for (const std::string& key : o.keys()) {
      std::optional<AxisName> a;
      if (key.size() == 1) a = axis_from_char(key[0]);
      const std::optional<int> idx = a ? m_.index_of(*a) : std::nullopt;
      if (!idx) o.fail(key, fmt::format("\"{}\" is not an axis of this machine", key));
      u[*idx] = to_internal(*a, o.number(key));
    }
    return u;
  }

  struct Common {
    int cycles = 1;
    double dwell_s = 1.0, move_s = 1.0, pause_s = 0.0;
    std::vector<double> feeds{0.0};
    std::uint8_t mask = 0;
    bool projection = false;
    Eigen::Vector3d beam = Eigen::Vector3d::Zero();
  };

  Common common(const JsonObject& t, std::uint8_t default_mask) {
    Common c;
    const double cycles = t.number_or("cycles", 1.0);
    if (cycles < 1 || cycles != std::floor(cycles) || cycles > 1e6)
      t.fail("cycles", "expected a whole number >= 1");
    c.cycles = static_cast<int>(cycles);
    c.dwell_s = t.number_or("dwell_s", 1.0);
    c.move_s = t.number_or("move_s", 1.0);
    c.pause_s = t.number_or("pause_s", 0.0);
    for (const char* k : {"dwell_s", "move_s", "pause_s"})
      if (t.has(k) && t.number(k) < 0) t.fail(k, "expected a number >= 0 (seconds)");
    if (t.has("feed_mm_min")) {
      c.feeds = t.values("feed_mm_min");
      for (double f : c.feeds)
        if (!(f > 0)) t.fail("feed_mm_min", "expected feeds > 0 (mm/min)");
      plan_.any_feed = true;
    }
    if (t.has("beam") && t.has("record"))
      t.fail("beam", "give either \"record\" (components) or \"beam\" (projection), not both");
    if (t.has("beam")) {
      const Eigen::Vector3d b = t.vec3("beam");
      if (b.norm() < 1e-9) t.fail("beam", "expected a non-zero direction");
      c.projection = true;
      c.beam = b.normalized();
      plan_.any_projection = true;
    } else if (t.has("record")) {
      const nlohmann::json& r = t.at("record");
      if (!r.is_array() || r.empty())
        t.fail("record", "expected a list such as [\"ex\", \"ey\", \"ez\"]");
      for (std::size_t k = 0; k < r.size(); ++k) {
        const std::string s = r[k].is_string() ? r[k].get<std::string>() : std::string();
        const int comp = s == "ex" ? 0 : s == "ey" ? 1 : s == "ez" ? 2 : -1;
        if (comp < 0) t.fail("record/" + std::to_string(k), "expected \"ex\", \"ey\" or \"ez\"");
        c.mask |= static_cast<std::uint8_t>(1u << comp);
      }
    } else {
      c.mask = default_mask;
    }
    plan_.record_union |= c.mask;
    return c;
  }

  /// Moves to u and takes a reading there (record: false, only moves).
  void visit(const JsonObject& t, const AxisVector& target, const Common& c, double feed,
             int forced_axis = -1, int forced_sign = 0, bool record = true) {
    if (++points_ > kMaxPlanPoints)
      t.fail("", fmt::format("the plan has more than {:g} points; use larger steps or fewer cycles",
                             kMaxPlanPoints));
    AxisVector u = target;
    for (int i = 0; i < m_.axis_count(); ++i)
      u[i] = quantize_recorded_position(m_.axis_order[static_cast<std::size_t>(i)], u[i]);
    try {
      check_within_travel(m_, u);
    } catch (const std::invalid_argument& e) {
      std::string at;
      for (int i = 0; i < m_.axis_count(); ++i) {
        const AxisName a = m_.axis_order[static_cast<std::size_t>(i)];
        at += fmt::format("{}{}={:g}", at.empty() ? "" : " ", axis_char(a),
                          is_rotary(a) ? u[i] / units::kRadPerDeg : u[i]);
      }
      t.fail("", fmt::format("planned point {} is outside travel ({}); change the test so every "
                             "point lies within the machine's travel",
                             at, e.what()));
    }
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    const ApproachDirections before = dir_;
    for (int i = 0; i < m_.axis_count(); ++i) {
      const AxisName a = m_.axis_order[static_cast<std::size_t>(i)];
      const double delta = u[i] - cur_[i];
      if (std::abs(delta) > kStill) dir_[static_cast<std::size_t>(i)] = delta > 0 ? 1 : -1;
      if (!is_rotary(a)) d[static_cast<int>(a)] = delta;
    }
    const double dist = d.norm();
    if (dist > kStill) move_dir_ = d / dist;
    if (forced_axis >= 0) {
      dir_[static_cast<std::size_t>(forced_axis)] = static_cast<std::int8_t>(forced_sign);
      const AxisName a = m_.axis_order[static_cast<std::size_t>(forced_axis)];
      move_dir_ = forced_sign * Eigen::Vector3d::Unit(static_cast<int>(a));
    }
    note_reversals(before, u);
    t_ += (feed > 0 && dist > kStill) ? dist / feed * 60.0 : c.move_s;
    t_ += c.dwell_s;
    cur_ = u;
    if (!record) return;
    PlannedPoint p;
    p.u = u;
    p.dir = dir_;
    p.t_s = t_;
    p.run = run_;
    p.feed_mm_min = feed;
    p.move_direction = move_dir_;
    p.since_reversal_mm = since_reversal_;
    p.record_mask = c.mask;
    p.projection = c.projection;
    p.beam = c.beam;
    plan_.points.push_back(p);
  }

  /// Where each linear axis last reversed (its position before the move
  /// that turned it), and how far it is from there at u.
  void note_reversals(const ApproachDirections& before, const AxisVector& u) {
    for (int i = 0; i < m_.axis_count(); ++i) {
      const AxisName a = m_.axis_order[static_cast<std::size_t>(i)];
      const std::size_t s = static_cast<std::size_t>(i);
      if (is_rotary(a)) continue;
      if (before[s] != 0 && dir_[s] != before[s]) reversed_at_[static_cast<int>(a)] = cur_[i];
      since_reversal_[static_cast<int>(a)] =
          std::isnan(reversed_at_[static_cast<int>(a)])
              ? INFINITY
              : std::abs(u[i] - reversed_at_[static_cast<int>(a)]);
    }
  }

  void expand_test(const JsonObject& t) {
    const std::string type = t.string("type");
    if (type == "laser") {
      expand_laser(t);
    } else if (type == "probe_ball") {
      expand_probe_ball(t);
    } else if (type == "grid") {
      expand_grid(t);
    } else if (type == "points") {
      expand_points(t);
    } else if (type == "circular") {
      expand_circular(t);
    } else {
      t.fail("type", fmt::format("unknown test type \"{}\"; expected laser, probe_ball, grid, "
                                 "points or circular",
                                 type));
    }
  }

  void expand_laser(const JsonObject& t) {
    t.allow_only({"type", "description", "axis", "from", "to", "step", "bidirectional", "cycles",
                  "at", "record", "beam", "dwell_s", "move_s", "pause_s", "feed_mm_min"});
    const AxisName axis = t.axis("axis");
    const std::optional<int> idx = m_.index_of(axis);
    if (!idx || is_rotary(axis)) t.fail("axis", "expected a linear axis of this machine");
    const Common c = common(t, static_cast<std::uint8_t>(1u << static_cast<int>(axis)));
    const double from = t.number("from"), to = t.number("to"), step = t.number("step");
    if (!(step > 0)) t.fail("step", "expected a number > 0 (mm)");
    if (from == to) t.fail("to", "expected to != from");
    const bool bidirectional = t.boolean_or("bidirectional", true);
    AxisVector base = cur_;
    if (t.has("at")) base = positions_from(t.object("at"), cur_);
    std::vector<double> targets;
    const double sign = to > from ? 1.0 : -1.0;
    const double count = std::floor(std::abs(to - from) / step + 1e-9);
    if (!(count <= kMaxPlanPoints)) t.fail("step", "too many points; use a larger step");
    const auto n = static_cast<long long>(count);
    for (long long k = 0; k <= n; ++k)
      targets.push_back(from + sign * static_cast<double>(k) * step);
    for (double feed : c.feeds) {
      for (int cycle = 0; cycle < c.cycles; ++cycle) {
        ++run_;
        for (double q : targets) {
          AxisVector u = base;
          u[*idx] = q;
          visit(t, u, c, feed, *idx, static_cast<int>(sign));
        }
        if (bidirectional)
          for (auto it = targets.rbegin(); it != targets.rend(); ++it) {
            AxisVector u = base;
            u[*idx] = *it;
            visit(t, u, c, feed, *idx, -static_cast<int>(sign));
          }
        t_ += c.pause_s;
      }
    }
  }

  /// "center_mm": [x, y, z] or "centers_mm": [[x, y, z], ...].
  std::vector<Eigen::Vector3d> ball_centres(const JsonObject& t) const {
    std::vector<Eigen::Vector3d> centres;
    if (t.has("center_mm") == t.has("centers_mm"))
      t.fail("", "give the ball centre as \"center_mm\": [x, y, z] or several as \"centers_mm\"");
    if (t.has("center_mm")) {
      centres.push_back(t.vec3("center_mm"));
    } else {
      const nlohmann::json& v = t.at("centers_mm");
      if (!v.is_array() || v.empty()) t.fail("centers_mm", "expected an array of [x, y, z]");
      for (std::size_t k = 0; k < v.size(); ++k) {
        nlohmann::json wrap = {{"c", v[k]}};
        const JsonObject w(file_, wrap, t.path_of("centers_mm") + "/" + std::to_string(k));
        try {
          centres.push_back(w.vec3("c"));
        } catch (const InputError&) {
          t.fail("centers_mm/" + std::to_string(k), "expected an array of three numbers [x, y, z]");
        }
      }
    }
    return centres;
  }

  void expand_probe_ball(const JsonObject& t) {
    t.allow_only({"type", "description", "center_mm", "centers_mm", "a_deg", "b_deg", "c_deg",
                  "cycles", "record", "beam", "dwell_s", "move_s", "pause_s", "feed_mm_min"});
    const Common c = common(t, 0b111);
    const std::vector<Eigen::Vector3d> centres = ball_centres(t);
    // Rotary angle lists, in machine axis order; outer loops first.
    std::vector<AxisValues> angles;
    for (int i = 0; i < m_.axis_count(); ++i) {
      const AxisName a = m_.axis_order[static_cast<std::size_t>(i)];
      if (!is_rotary(a)) continue;
      const std::string key = std::string(1, static_cast<char>(axis_char(a) - 'A' + 'a')) + "_deg";
      std::vector<double> list{m_.home[i] / units::kRadPerDeg};
      if (t.has(key)) list = t.values(key);
      angles.push_back({i, list});
    }
    for (const char* k : {"a_deg", "b_deg", "c_deg"}) {
      const std::optional<AxisName> a = axis_from_char(static_cast<char>(k[0] - 'a' + 'A'));
      if (t.has(k) && !m_.index_of(*a)) t.fail(k, "this machine has no such rotary axis");
    }
    if (angles.empty()) t.fail("type", "a probe-ball test needs a machine with rotary axes");
    for (double feed : c.feeds)
      for (int cycle = 0; cycle < c.cycles; ++cycle) {
        for (const Eigen::Vector3d& centre : centres) {
          ++run_;
          std::vector<std::size_t> k(angles.size(), 0);
          do {
            AxisVector u = cur_;
            for (std::size_t j = 0; j < angles.size(); ++j)
              u[angles[j].index] = angles[j].values[k[j]] * units::kRadPerDeg;
            AxisVector placed;
            try {
              placed = linear_axes_for_tip(m_, u, centre);
            } catch (const std::invalid_argument& e) {
              t.fail("", e.what());
            }
            visit(t, placed, c, feed);
          } while (next_combination(k, angles));
        }
        t_ += c.pause_s;
      }
  }

  void expand_grid(const JsonObject& t) {
    t.allow_only({"type", "description", "axes", "cycles", "record", "beam", "dwell_s", "move_s",
                  "pause_s", "feed_mm_min"});
    const Common c = common(t, 0b111);
    const JsonObject axes = t.object("axes");
    std::vector<AxisValues> lists;
    for (int i = 0; i < m_.axis_count(); ++i) {
      const AxisName a = m_.axis_order[static_cast<std::size_t>(i)];
      std::vector<double> list{m_.home[i] / (is_rotary(a) ? units::kRadPerDeg : 1.0)};
      if (axes.has(axis_key(a))) list = axes.values(axis_key(a));
      lists.push_back({i, list});
    }
    for (const std::string& key : axes.keys()) {
      std::optional<AxisName> a;
      if (key.size() == 1) a = axis_from_char(key[0]);
      if (!a || !m_.index_of(*a))
        axes.fail(key, fmt::format("\"{}\" is not an axis of this machine", key));
    }
    for (double feed : c.feeds)
      for (int cycle = 0; cycle < c.cycles; ++cycle) {
        ++run_;
        std::vector<std::size_t> k(lists.size(), 0);
        do {
          AxisVector u = cur_;
          for (std::size_t j = 0; j < lists.size(); ++j) {
            const AxisName a = m_.axis_order[static_cast<std::size_t>(lists[j].index)];
            u[lists[j].index] = to_internal(a, lists[j].values[k[j]]);
          }
          visit(t, u, c, feed);
        } while (next_combination(k, lists));
        t_ += c.pause_s;
      }
  }

  void expand_points(const JsonObject& t) {
    t.allow_only({"type", "description", "positions", "cycles", "record", "beam", "dwell_s",
                  "move_s", "pause_s", "feed_mm_min"});
    const Common c = common(t, 0b111);
    const nlohmann::json& v = t.at("positions");
    if (!v.is_array() || v.empty()) t.fail("positions", "expected an array of axis positions");
    std::vector<AxisVector> us;
    for (std::size_t k = 0; k < v.size(); ++k) {
      const std::string p = "positions/" + std::to_string(k);
      if (!v[k].is_array() || static_cast<int>(v[k].size()) != m_.axis_count())
        t.fail(p,
               fmt::format("expected {} numbers, one per axis in the machine's order (mm, degrees)",
                           m_.axis_count()));
      AxisVector u(m_.axis_count());
      for (int i = 0; i < m_.axis_count(); ++i) {
        const nlohmann::json& x = v[k][static_cast<std::size_t>(i)];
        if (!x.is_number() || !std::isfinite(x.get<double>()))
          t.fail(p + "/" + std::to_string(i), "expected a finite number");
        u[i] = to_internal(m_.axis_order[static_cast<std::size_t>(i)], x.get<double>());
      }
      us.push_back(u);
    }
    for (double feed : c.feeds)
      for (int cycle = 0; cycle < c.cycles; ++cycle) {
        ++run_;
        for (const AxisVector& u : us) visit(t, u, c, feed);
        t_ += c.pause_s;
      }
  }

  /// A circular test (ISO 230-4, circular_test.h): each cycle and feed runs
  /// counter-clockwise, then clockwise ("direction": "both"), each a run.
  void expand_circular(const JsonObject& t) {
    t.allow_only({"type", "description", "plane", "center", "radius_mm", "direction", "start_deg",
                  "step_deg", "overshoot_deg", "cycles", "dwell_s", "pause_s", "feed_mm_min"});
    if (!t.has("feed_mm_min")) t.fail("", "a circular test needs \"feed_mm_min\"");
    Common c = common(t, 0);
    if (!t.has("dwell_s")) c.dwell_s = 0;
    c.projection = true;
    plan_.any_projection = true;
    const std::string plane = t.string_or("plane", "XY");
    const std::optional<AxisName> a1 = plane.size() == 2 ? axis_from_char(plane[0]) : std::nullopt,
                                  a2 = plane.size() == 2 ? axis_from_char(plane[1]) : std::nullopt;
    if (!a1 || !a2) t.fail("plane", "expected two axis letters such as \"XY\", \"YZ\" or \"ZX\"");
    CircularTestPath path{.first = *a1, .second = *a2, .centre = cur_};
    if (t.has("center")) path.centre = positions_from(t.object("center"), cur_);
    path.radius_mm = t.number("radius_mm");
    path.start_deg = t.number_or("start_deg", 0.0);
    path.step_deg = t.number_or("step_deg", 1.0);
    path.overshoot_deg = t.number_or("overshoot_deg", 90.0);
    const std::string direction = t.string_or("direction", "both");
    if (direction != "both" && direction != "ccw" && direction != "cw")
      t.fail("direction", "expected \"both\", \"ccw\" or \"cw\"");
    std::vector<bool> senses;
    if (direction != "cw") senses.push_back(true);
    if (direction != "ccw") senses.push_back(false);
    for (double feed : c.feeds)
      for (int cycle = 0; cycle < c.cycles; ++cycle)
        for (bool ccw : senses) {
          ++run_;
          std::vector<CircularStop> stops;
          try {
            stops = circular_run(m_, path, ccw);
          } catch (const std::invalid_argument& e) {
            t.fail("", e.what());
          }
          for (const CircularStop& s : stops) {
            c.beam = s.radial;
            visit(t, s.u, c, feed, -1, 0, s.capture);
          }
          t_ += c.pause_s;
        }
  }

  std::string file_;
  const Machine& m_;
  Plan plan_;
  AxisVector cur_;
  ApproachDirections dir_{};
  Eigen::Vector3d move_dir_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d reversed_at_ = Eigen::Vector3d::Constant(NAN);          ///< X, Y, Z
  Eigen::Vector3d since_reversal_ = Eigen::Vector3d::Constant(INFINITY);  ///< X, Y, Z
  double t_ = 0.0;
  int run_ = 0;
  double points_ = 0;  ///< readings planned so far (bounded by kMaxPlanPoints)
};

}  // namespace

double PlannedTemperature::at(double t_s) const {
  double T = start_c + rate_c_per_h * t_s / 3600.0;
  if (tau_s > 0) T += rise_c * (1.0 - std::exp(-t_s / tau_s));
  return T;
}

Plan read_plan_json(std::istream& in, const std::string& file, const Machine& m) {
  const nlohmann::json doc = parse_json_document(in, file);
  return Expander(file, m).expand(doc);
}

Plan load_plan_json(const std::string& path, const Machine& m) {
  if (path == "-") return read_plan_json(std::cin, "<stdin>", m);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open the plan; check the path and the permissions");
  return read_plan_json(in, path, m);
}

}  // namespace volmap
