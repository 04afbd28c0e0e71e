#include "core/model/machine_json.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "core/common/input_error.h"
#include "core/common/json_input.h"
#include "core/common/units.h"

namespace volmap {
namespace {

using nlohmann::json;

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void fail(const std::string& path, const std::string& msg) const {
    throw InputError::at_json_path(file_, path, msg);
  }

  /// Every key of object `obj` (at `path`) is one of `allowed`: a misspelt
  /// key is an error, never ignored (it would change the machine).
  void only(const json& obj, const std::string& path,
            std::initializer_list<const char*> allowed) const {
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      bool ok = false;
      for (const char* a : allowed) ok = ok || it.key() == a;
      if (!ok)
        fail((path == "/" ? "" : path) + "/" + it.key(), unknown_key_message(it.key(), allowed));
    }
  }

  const json& member(const json& obj, const std::string& path, const char* key) const {
    auto it = obj.find(key);
    if (it == obj.end()) fail(path, fmt::format("missing required key \"{}\"", key));
    return *it;
  }

  double number(const json& v, const std::string& path) const {
    if (!v.is_number()) fail(path, "expected a number");
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(path, "expected a finite number");
    return x;
  }

  Eigen::Vector3d vec3(const json& v, const std::string& path) const {
    if (!v.is_array() || v.size() != 3) fail(path, "expected an array of three numbers [x, y, z]");
    return {number(v[0], path + "/0"), number(v[1], path + "/1"), number(v[2], path + "/2")};
  }

  Eigen::Vector3d unit3(const json& v, const std::string& path) const {
    Eigen::Vector3d d = vec3(v, path);
    const double n = d.norm();
    if (std::abs(n - 1.0) > 1e-9)
      fail(path, fmt::format("expected a unit vector, its length is {:g}", n));
    return d / n;
  }

  AxisName axis_name(const json& v, const std::string& path) const {
    if (!v.is_string() || v.get<std::string>().size() != 1 ||
        !axis_from_char(v.get<std::string>()[0]))
      fail(path, "expected an axis letter: one of X Y Z A B C");
    return *axis_from_char(v.get<std::string>()[0]);
  }

  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

struct AxisSpec {
  bool rotary = false;
  Eigen::Vector3d direction;
  AxisLimits limits;
  double home = 0.0;
  bool used = false;
};

/// The JSON document of `text`; malformed JSON is an InputError at its line
/// and column.
json parse_machine_document(const std::string& text, const std::string& file) {
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    const auto [line, col] = json_error_line_column(text, e.byte);
    std::string what = e.what();
    // nlohmann's message: "[json.exception.parse_error.101] parse error at
    // line 1, column 2: syntax error ..."; keep the part after the position.
    const size_t colon = what.find(": ", what.find("parse error"));
    if (colon != std::string::npos) what = what.substr(colon + 2);
    throw InputError(file, line, col, "malformed JSON: " + what + "; fix the syntax");
  } catch (const json::out_of_range&) {
    throw_json_number_overflow(text, file);
  }
}

/// One entry of /axes: type, direction, travel and home (internal units).
AxisSpec read_axis(const Reader& r, AxisName a, const json& ax, const std::string& path) {
  if (!ax.is_object()) r.fail(path, "expected an object");
  r.only(ax, path, {"type", "direction", "travel_mm", "travel_deg", "home_mm", "home_deg"});
  AxisSpec s;
  const json& type = r.member(ax, path, "type");
  if (type == "linear")
    s.rotary = false;
  else if (type == "rotary")
    s.rotary = true;
  else
    r.fail(path + "/type", "expected \"linear\" or \"rotary\"");
  if (s.rotary != is_rotary(a))
    r.fail(path + "/type", fmt::format("axis {} is {} by ISO 841 naming", axis_char(a),
                                       is_rotary(a) ? "rotary" : "linear"));
  s.direction = r.unit3(r.member(ax, path, "direction"), path + "/direction");
  const char* travel_key = s.rotary ? "travel_deg" : "travel_mm";
  const double k = s.rotary ? units::kRadPerDeg : 1.0;
  const json& travel = r.member(ax, path, travel_key);
  const std::string tpath = path + "/" + travel_key;
  if (travel.is_null()) {
    if (!s.rotary) r.fail(tpath, "a linear axis needs a finite travel [min, max]");
    s.limits.unlimited = true;
  } else {
    if (!travel.is_array() || travel.size() != 2)
      r.fail(tpath, "expected [min, max] (or null for an unlimited rotary axis)");
    s.limits.min = r.number(travel[0], tpath + "/0") * k;
    s.limits.max = r.number(travel[1], tpath + "/1") * k;
    if (!(s.limits.min < s.limits.max)) r.fail(tpath, "expected min < max");
  }
  const char* home_key = s.rotary ? "home_deg" : "home_mm";
  if (auto h = ax.find(home_key); h != ax.end()) {
    s.home = r.number(*h, path + "/" + home_key) * k;
    if (!s.limits.unlimited && (s.home < s.limits.min || s.home > s.limits.max))
      r.fail(path + "/" + home_key, "home lies outside the travel");
  } else {
    s.home = s.limits.unlimited ? 0.0 : std::clamp(0.0, s.limits.min, s.limits.max);
  }
  return s;
}

using AxisSpecs = std::array<std::optional<AxisSpec>, kAxisNameCount>;

/// /axes into `spec`, and the machine's axis order, limits and home.
AxisSpecs read_axes(const Reader& r, const json& doc, Machine& m) {
  const json& axes = r.member(doc, "/", "axes");
  if (!axes.is_object() || axes.empty())
    r.fail("/axes", "expected an object of axes, e.g. {\"X\": {...}}");
  AxisSpecs spec;
  for (auto it = axes.begin(); it != axes.end(); ++it) {
    const std::string path = "/axes/" + it.key();
    if (it.key().size() != 1 || !axis_from_char(it.key()[0]))
      r.fail(path, "unknown axis name: use X Y Z A B C");
    const AxisName a = *axis_from_char(it.key()[0]);
    spec[static_cast<size_t>(a)] = read_axis(r, a, it.value(), path);
  }
  for (int i = 0; i < kAxisNameCount; ++i) {
    if (!spec[static_cast<size_t>(i)]) continue;
    const AxisSpec& s = *spec[static_cast<size_t>(i)];
    m.axis_order.push_back(static_cast<AxisName>(i));
    m.limits.push_back(s.limits);
  }
  m.home.resize(m.axis_count());
  for (int i = 0; i < m.axis_count(); ++i)
    m.home[i] = spec[static_cast<size_t>(m.axis_order[static_cast<size_t>(i)])]->home;
  return spec;
}

/// The joints of the chain under `key`, base first; each axis is used once.
void read_chain(const Reader& r, const json& doc, const char* key, AxisSpecs& spec,
                const Machine& m, std::vector<Joint>& chain) {
  const std::string path = std::string("/") + key;
  const json& c = r.member(doc, "/", key);
  if (!c.is_array()) r.fail(path, "expected an array of joints, base first");
  for (size_t i = 0; i < c.size(); ++i) {
    const std::string jp = path + "/" + std::to_string(i);
    if (!c[i].is_object()) r.fail(jp, "expected {\"axis\": ..., \"offset_mm\": [...]}");
    r.only(c[i], jp, {"axis", "offset_mm"});
    Joint j;
    j.axis = r.axis_name(r.member(c[i], jp, "axis"), jp + "/axis");
    auto& s = spec[static_cast<size_t>(j.axis)];
    if (!s)
      r.fail(jp + "/axis", fmt::format("axis {} is not defined under /axes", axis_char(j.axis)));
    if (s->used)
      r.fail(jp + "/axis", fmt::format("axis {} appears twice in the chains", axis_char(j.axis)));
    s->used = true;
    j.rotary = s->rotary;
    j.direction_parent = s->direction;
    if (auto o = c[i].find("offset_mm"); o != c[i].end())
      j.offset_parent_mm = r.vec3(*o, jp + "/offset_mm");
    j.index = *m.index_of(j.axis);
    chain.push_back(j);
  }
}

/// Origins and /tool.
void read_offsets_and_tool(const Reader& r, const json& doc, Machine& m) {
  if (auto it = doc.find("workpiece_origin_mm"); it != doc.end())
    m.workpiece_origin_mm = r.vec3(*it, "/workpiece_origin_mm");
  if (auto it = doc.find("spindle_offset_mm"); it != doc.end())
    m.spindle_offset_mm = r.vec3(*it, "/spindle_offset_mm");
  const json& tool = r.member(doc, "/", "tool");
  if (!tool.is_object()) r.fail("/tool", "expected {\"length_mm\": ..., \"axis\": [...]}");
  r.only(tool, "/tool", {"length_mm", "axis"});
  m.tool_length_mm = r.number(r.member(tool, "/tool", "length_mm"), "/tool/length_mm");
  if (m.tool_length_mm < 0) r.fail("/tool/length_mm", "a tool length cannot be negative");
  if (auto it = tool.find("axis"); it != tool.end()) m.tool_axis = r.unit3(*it, "/tool/axis");
}

/// The machine's axis named by a one-letter `key`, or an InputError at `path`.
AxisName machine_axis(const Reader& r, const Machine& m, const std::string& key,
                      const std::string& path) {
  if (key.size() != 1 || !axis_from_char(key[0]) || !m.index_of(*axis_from_char(key[0])))
    r.fail(path, "not an axis of this machine");
  return *axis_from_char(key[0]);
}

/// Measurement poses of the kinematic-parameter-independent model.
void read_measured_at(const Reader& r, const json& doc, Machine& m) {
  m.measured_at.assign(static_cast<size_t>(m.axis_count()), m.home);
  auto it = doc.find("measured_at");
  if (it == doc.end()) return;
  if (!it->is_object()) r.fail("/measured_at", "expected {\"Y\": {\"X\": 500, \"Z\": 0}, ...}");
  for (auto e = it->begin(); e != it->end(); ++e) {
    const std::string path = "/measured_at/" + e.key();
    const AxisName measured = machine_axis(r, m, e.key(), path);
    if (is_rotary(measured))
      r.fail(path, "only linear axes are measured at the tool tip (Hsu III.B)");
    if (!e.value().is_object()) r.fail(path, "expected {\"X\": position, ...}");
    AxisVector& pose = m.measured_at[static_cast<size_t>(*m.index_of(measured))];
    for (auto p = e.value().begin(); p != e.value().end(); ++p) {
      const std::string pp = path + "/" + p.key();
      const AxisName other = machine_axis(r, m, p.key(), pp);
      if (other == measured) r.fail(pp, "the measured axis itself moves; give the other axes");
      pose[*m.index_of(other)] =
          r.number(p.value(), pp) * (is_rotary(other) ? units::kRadPerDeg : 1.0);
    }
  }
}

/// /structure, when given, must be the structure code the chains describe.
void check_structure(const Reader& r, const json& doc, const Machine& m) {
  auto it = doc.find("structure");
  if (it == doc.end()) return;
  if (!it->is_string()) r.fail("/structure", "expected a string such as \"[w C' A' X' Y' b Z t]\"");
  // Compare ignoring spaces.
  auto squash = [](std::string s) {
    std::string o;
    for (char ch : s)
      if (ch != ' ') o += ch;
    return o;
  };
  if (squash(it->get<std::string>()) != squash(m.structure_code()))
    r.fail("/structure", fmt::format("the chains describe {}, not {}", m.structure_code(),
                                     it->get<std::string>()));
}

}  // namespace

Machine read_machine_json(std::istream& in, const std::string& file) {
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const json doc = parse_machine_document(text, file);

  Reader r(file);
  if (!doc.is_object()) r.fail("/", "expected a JSON object (a machine)");
  const json& fmt_v = r.member(doc, "/", "format");
  if (!fmt_v.is_string() || fmt_v.get<std::string>() != "volmap-machine/1")
    r.fail("/format", "expected \"volmap-machine/1\"");
  r.only(doc, "/",
         {"format", "name", "description", "structure", "axes", "workpiece_chain", "tool_chain",
          "workpiece_origin_mm", "spindle_offset_mm", "tool", "measured_at"});

  Machine m;
  if (auto it = doc.find("name"); it != doc.end()) {
    if (!it->is_string()) r.fail("/name", "expected a string");
    m.name = it->get<std::string>();
  }
  if (auto it = doc.find("description"); it != doc.end()) {
    if (!it->is_string()) r.fail("/description", "expected a string");
    m.description = it->get<std::string>();
  }
  AxisSpecs spec = read_axes(r, doc, m);
  read_chain(r, doc, "workpiece_chain", spec, m, m.workpiece_chain);
  read_chain(r, doc, "tool_chain", spec, m, m.tool_chain);
  for (AxisName a : m.axis_order)
    if (!spec[static_cast<size_t>(a)]->used)
      r.fail(std::string("/axes/") + axis_char(a),
             "axis is in no chain: add it to workpiece_chain or tool_chain");
  read_offsets_and_tool(r, doc, m);
  read_measured_at(r, doc, m);
  check_structure(r, doc, m);
  return m;
}

Machine load_machine_json(const std::string& path) {
  if (path == "-") return read_machine_json(std::cin, "<stdin>");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open the machine file; check the path");
  return read_machine_json(in, path);
}

}  // namespace volmap
