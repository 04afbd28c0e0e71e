#include "gcode/flatten/parameters.h"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "gcode/g_codes.h"
#include "gcode/nc_interpreter.h"

namespace volmap::nc::flatten {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

// The system parameters LinuxCNC fills at run time from the machine: no
// offline post can know them.
std::optional<std::string> run_time_parameter(int n) {
  if (n >= 5061 && n <= 5070) return "a probe result (G38.x)";
  if (n == 5399) return "the result of M66 (a digital or analog input)";
  if (n == 5600 || n == 5601) return "the tool changer's fault state";
  return std::nullopt;
}

}  // namespace

Parameters::Parameters(const Interpreter& interp)
    : interp_(interp), numbered_(kParameterCount, 0.0), frames_(1) {}

namespace {
// The tool in the spindle (#5400, #<_current_tool>): after M61 LinuxCNC's
// rs274 still gives the last M6's, a machine M61's; neither is safe to use.
double current_tool(const State& s) {
  if (s.tool_from_m61)
    throw ValueError{
        "the current tool (#5400, #<_current_tool>) after M61: LinuxCNC's interpreter gives "
        "the tool the last M6 loaded, a machine the tool M61 named; load it with M6 or write "
        "the tool number"};
  return s.tool;
}
}  // namespace

void Parameters::load(int number, double value) {
  if (number >= 1 && number < kParameterCount) numbered_[static_cast<size_t>(number)] = value;
}

std::optional<double> Parameters::system(int n) const {
  const State& s = interp_.state();
  if (const auto what = run_time_parameter(n); what && !written_.contains(n))
    throw ValueError{fmt::format(
        "#{} is {}, known only on the machine at run time; the post cannot follow a program "
        "whose moves depend on it",
        n, *what)};
  if ((n >= 5161 && n <= 5166) || (n >= 5181 && n <= 5186)) {
    const int k = n >= 5181 ? 1 : 0, a = n - (k == 0 ? 5161 : 5181);
    if (s.home_known[static_cast<size_t>(k)][static_cast<size_t>(a)])
      return a < 3 ? s.home[static_cast<size_t>(k)][static_cast<size_t>(a)]
                   : s.home[static_cast<size_t>(k)][static_cast<size_t>(a)] * kDegPerRad;
    return std::nullopt;
  }
  if (n == 5220) return s.coord_system + 1;
  if (n == 5210) return s.g92_applied ? 1.0 : 0.0;
  if (n >= 5211 && n <= 5213) return s.g92_mm[n - 5211];
  if (n >= 5221 && n <= 5390) {
    // G54 from 5221, each system 20 further: X Y Z A B C U V W, R at +9.
    const int k = (n - 5221) / 20, a = (n - 5221) % 20;
    if (k < 9 && a < 3) return s.coord_offset_mm[static_cast<size_t>(k)][a];
    return std::nullopt;  // the stored value (a .var file's, or 0)
  }
  if (n == 5400) return current_tool(s);
  if (n >= 5401 && n <= 5410) {
    // The loaded tool's row of the tool table (rs274: its Z and diameter as
    // the table gives them, whatever G43 applies; other columns zero here).
    if (!s.tool_loaded)
      throw ValueError{fmt::format(
          "#{} before any M6 reads the tool the machine holds when the program starts, known "
          "only at run time; load the tool with M6 first",
          n)};
    const int tool = static_cast<int>(current_tool(s));
    const auto& table =
        n == 5410 ? interp_.setup().tool_diameter_mm : interp_.setup().tool_length_mm;
    const auto it = table.find(tool);
    return (n == 5403 || n == 5410) && it != table.end() ? it->second : 0.0;
  }
  if (n >= 5420 && n <= 5428 && s.comp_side != 0)
    throw ValueError{
        fmt::format("#{} (the current position) with cutter radius compensation on: "
                    "LinuxCNC refuses to read it there",
                    n)};
  if (n >= 5420 && n <= 5428) {
    const int a = n - 5420;
    if (a < 3) {
      if (!s.axis_known[static_cast<size_t>(a)])
        throw ValueError{fmt::format(
            "#{} (the current {} position) is not known here: the program has not commanded {} "
            "yet; command it first, or give `initial_position`",
            n, "XYZ"[a], "XYZ"[a])};
      return (s.position_mm[a] - s.origin_mm[a]) / s.unit_mm;
    }
    if (a < 6) return s.rotary_rad[static_cast<size_t>(a - 3)] * kDegPerRad;
    return 0.0;
  }
  return std::nullopt;
}

double Parameters::get(int n) const {
  if (n < 1 || n >= kParameterCount)
    throw ValueError{
        fmt::format("parameter number {} is out of range (1 to {})", n, kParameterCount - 1)};
  if (n >= 5000)
    if (const auto v = system(n)) return *v;
  return numbered_[static_cast<size_t>(n)];
}

std::optional<double> Parameters::predefined(std::string_view name) const {
  const State& s = interp_.state();
  auto flag = [](bool b) { return b ? 1.0 : 0.0; };
  if (name == "_value") return value_;
  if (name == "_value_returned") return flag(value_returned_);
  if (name == "_call_level") return call_level();
  if (name == "_metric") return flag(s.unit_mm == 1.0);
  if (name == "_imperial") return flag(s.unit_mm != 1.0);
  if (name == "_absolute") return flag(s.absolute);
  if (name == "_incremental") return flag(!s.absolute);
  if (name == "_inverse_time") return flag(s.feed_mode == kG93InverseTime);
  if (name == "_units_per_minute") return flag(s.feed_mode == kG94UnitsPerMinute);
  if (name == "_units_per_rev") return flag(s.feed_mode == kG95UnitsPerRevolution);
  if (name == "_ijk_absolute_mode") return flag(s.arc_absolute);
  if (name == "_retract_r_plane") return flag(!s.g98);
  if (name == "_retract_old_z") return flag(s.g98);
  if (name == "_tool_offset") return flag(s.tool_length_active);
  if (name == "_plane") return 170.0 + 10.0 * s.plane;
  if (name == "_motion_mode") return s.motion;
  if (name == "_coord_system") {
    static constexpr int kCodes[] = {540, 550, 560, 570, 580, 590, 591, 592, 593};
    return kCodes[s.coord_system];
  }
  if (name == "_feed") return s.feed;
  if (name == "_current_tool") return current_tool(s);
  if (name == "_selected_tool") return s.selected_tool;
  // LinuxCNC's task runs the program on the machine (1); its previews and
  // rs274 see 0. volmap posts for the machine.
  if (name == "_task") return 1.0;
  for (int a = 0; a < 3; ++a) {
    const std::string axis(1, "xyz"[a]);
    if (name == "_" + axis) return get(5420 + a);
    if (name == "_abs_" + axis) {
      if (!s.axis_known[static_cast<size_t>(a)]) (void)get(5420 + a);  // its refusal
      return s.position_mm[a] / s.unit_mm;
    }
  }
  return std::nullopt;
}

double Parameters::get(std::string_view name) const {
  if (name.starts_with("_hal[") || name.starts_with("_ini[") || name.starts_with("_hal."))
    throw ValueError{fmt::format(
        "#<{}> is read from the machine's configuration or HAL at run time; the post cannot "
        "know it: replace it with its value",
        name)};
  if (name.starts_with('_')) {
    if (const auto it = global_.find(name); it != global_.end()) return it->second;
    if (const auto v = predefined(name)) return *v;
  } else {
    const auto& local = frames_.back().named;
    if (const auto it = local.find(name); it != local.end()) return it->second;
  }
  throw ValueError{
      fmt::format("named parameter #<{}> is not defined; set it before reading it", name)};
}

bool Parameters::exists(std::string_view name) const {
  if (name.starts_with('_')) return global_.contains(name) || predefined(name).has_value();
  return frames_.back().named.contains(name);
}

void Parameters::queue(int number, double value) {
  if (number < 1 || number >= kParameterCount)
    throw ValueError{
        fmt::format("parameter number {} is out of range (1 to {})", number, kParameterCount - 1)};
  if ((number >= 5400 && number <= 5413) || (number >= 5420 && number <= 5428))
    throw ValueError{fmt::format("#{} is read-only (LinuxCNC refuses to set it)", number)};
  if (number >= 5161 && number <= 5390)
    throw ValueError{fmt::format(
        "#{} holds a home position or an offset: setting it directly is not supported (the "
        "controller applies it when the coordinate system is next selected); use G10 L2, G28.1 "
        "or G30.1",
        number)};
  queued_numbered_.emplace_back(number, value);
}

void Parameters::queue(std::string name, double value) {
  if (name.starts_with('_') && predefined(name).has_value() && !global_.contains(name))
    throw ValueError{fmt::format("#<{}> is predefined and read-only", name)};
  // rs274 creates the parameter (0) as it reads the assignment: later on
  // the same line it reads 0, not "not defined".
  auto& scope = name.starts_with('_') ? global_ : frames_.back().named;
  scope.try_emplace(name, 0.0);
  queued_named_.emplace_back(std::move(name), value);
}

void Parameters::commit() {
  for (const auto& [n, v] : queued_numbered_) {
    numbered_[static_cast<size_t>(n)] = v;
    if (n >= 5000) written_.insert(n);
  }
  for (auto& [name, v] : queued_named_) {
    if (name.starts_with('_'))
      global_[name] = v;
    else
      frames_.back().named[name] = v;
  }
  queued_numbered_.clear();
  queued_named_.clear();
}

void Parameters::push_call(const std::vector<double>& args) {
  Frame f;
  for (int k = 0; k < kArgumentCount; ++k) {
    double& p = numbered_[static_cast<size_t>(k + 1)];
    f.args[static_cast<size_t>(k)] = p;
    p = static_cast<size_t>(k) < args.size() ? args[static_cast<size_t>(k)] : 0.0;
  }
  frames_.push_back(std::move(f));
  value_returned_ = false;
}

void Parameters::pop_call() {
  const Frame& f = frames_.back();
  for (int k = 0; k < kArgumentCount; ++k)
    numbered_[static_cast<size_t>(k + 1)] = f.args[static_cast<size_t>(k)];
  frames_.pop_back();
}

void Parameters::set_return(std::optional<double> value) {
  value_returned_ = value.has_value();
  value_ = value.value_or(0.0);
}

}  // namespace volmap::nc::flatten
