// volmap convert: an errors CSV's location errors from one meaning to the
// other, ISO 230-1 <-> Lei & Hsu's link errors (docs/model.md, "Location
// errors"; core/model/location_convention.h).
#include <fmt/format.h>

#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli/commands.h"
#include "cli/parse_util.h"
#include "core/common/atomic_file.h"
#include "core/common/csv.h"
#include "core/common/units.h"
#include "core/model/errors_csv.h"
#include "core/model/location_convention.h"
#include "core/model/machine_json.h"

namespace volmap::cli {

namespace {

bool is_location_header(std::string_view line) {
  std::string_view first = csv::split_cells(line).front().text;
  if (first.starts_with("\xEF\xBB\xBF")) first.remove_prefix(3);
  return !(first.size() == 1 && axis_from_char(first[0]).has_value());
}

/// The location blocks of `converted`, one per axis in chain order.
std::string location_blocks(const Machine& m, const ErrorSet& converted) {
  std::string text;
  std::vector<AxisName> order;
  for (const Joint& j : m.workpiece_chain) order.push_back(j.axis);
  for (const Joint& j : m.tool_chain) order.push_back(j.axis);
  for (AxisName a : order) {
    std::string header, row;
    for (int c = 0; c < kComponentCount; ++c) {
      const std::string name = error_name_string({static_cast<Component>(c), a, true});
      const auto it = converted.location.find(name);
      if (it == converted.location.end()) continue;
      const double scale = c < 3 ? units::kUmPerMm : units::kUradPerRad;
      header += (header.empty() ? "" : ",") + name;
      row += (row.empty() ? "" : ",") + fmt::format("{:.6f}", it->second * scale);
    }
    if (!header.empty()) text += "\n" + header + "\n" + row + "\n";
  }
  return text;
}

/// The input's text with its `# convention:` line and location blocks
/// (and the comments inside them) replaced: every other line as it was.
std::string rewrite(const std::string& input, const Machine& m, const ErrorSet& converted) {
  const std::vector<std::string> lines = csv::split_lines(input);
  std::string head, body;
  bool seen_block = false, in_block = false, drop_block = false;
  std::string pending_blank;
  for (const std::string& line : lines) {
    if (csv::is_blank(line)) {
      in_block = false;
      drop_block = false;
      if (seen_block) pending_blank = "\n";
      continue;
    }
    if (csv::is_comment(line)) {
      const auto meta = csv::parse_metadata_comment(csv::trim(line));
      if (meta && meta->key == "convention") continue;  // written anew
      if (!seen_block) {
        head += line + "\n";
      } else if (!drop_block) {
        body += pending_blank + line + "\n";
        pending_blank.clear();
      }
      continue;
    }
    if (!in_block) {
      in_block = true;
      seen_block = true;
      drop_block = is_location_header(line);
    }
    if (drop_block) continue;
    body += pending_blank + line + "\n";
    pending_blank.clear();
  }
  std::string out = head;
  out += fmt::format("# convention: {}\n", location_convention_name(converted.convention));
  if (body.starts_with("\n")) body.erase(0, 1);
  return out + "\n" + body + location_blocks(m, converted);
}

std::string parts_text(const Eigen::Isometry3d& T) {
  Eigen::Vector3d t_um, a_urad;
  small_transform_parts(T, t_um, a_urad);
  return fmt::format("shift ({:.3f}, {:.3f}, {:.3f}) µm, turn ({:.3f}, {:.3f}, {:.3f}) µrad",
                     t_um.x(), t_um.y(), t_um.z(), a_urad.x(), a_urad.y(), a_urad.z());
}

nlohmann::ordered_json parts_json(const Eigen::Isometry3d& T) {
  Eigen::Vector3d t_um, a_urad;
  small_transform_parts(T, t_um, a_urad);
  return {{"shift_um", {t_um.x(), t_um.y(), t_um.z()}},
          {"turn_urad", {a_urad.x(), a_urad.y(), a_urad.z()}}};
}

Runner register_convert(CLI::App& app) {
  struct Opts {
    std::string machine, errors, output, to, model = "independent";
    bool json = false, other_machine_errors = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* sub = app.add_subcommand(
      "convert",
      "Re-express an errors CSV's location errors in the other meaning: ISO 230-1 "
      "(errors.md) or Lei & Hsu's link errors; reports the rigid set-up part between them");
  sub->add_option("--machine", o->machine, "Machine definition (JSON, docs/machine-format.md)")
      ->required();
  sub->add_option("--errors", o->errors, "Errors CSV to convert (errors.md)")->required();
  sub->add_option("--to", o->to, "iso230-1 or link")
      ->required()
      ->check(CLI::IsMember({"iso230-1", "link"}));
  sub->add_option("-o,--output", o->output, "Errors CSV to write ('-' for standard output)")
      ->required();
  sub->add_option("--model", o->model,
                  "independent (default) or dependent: where a squareness turns (docs/model.md)")
      ->check(CLI::IsMember({"independent", "dependent"}));
  add_other_machine_flag(*sub, o->other_machine_errors);
  sub->add_flag("--json", o->json, "Write the report as one JSON document");
  sub->footer(
      "Example:\n  volmap convert --machine samples/machines/lei-hsu-xyzac.json "
      "--errors samples/errors/lei-hsu-xyzac.csv --to link -o link.csv");
  return [o]() -> int {
    refuse_output_equal_to_input(o->output, {o->machine, o->errors});
    const Machine m = load_machine_json(o->machine);
    const ErrorSet errors =
        load_errors_for(m, o->machine, o->errors, ErrorsFormat::kVolmap, o->other_machine_errors);
    const Formulation f =
        o->model == "dependent" ? Formulation::kDependent : Formulation::kIndependent;
    const LocationConvention to = *parse_location_convention(o->to);
    const ConventionConversion r = convert_location_convention(m, errors, to, f);
    std::ifstream in(o->errors, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const bool same = errors.convention == to;
    AtomicOutput out(o->output, {o->machine, o->errors});
    out.stream() << (same ? text : rewrite(text, m, r.errors));
    out.commit();
    std::ostream& report = o->output == "-" ? std::cerr : std::cout;
    if (o->json) {
      nlohmann::ordered_json doc;
      doc["from"] = location_convention_name(errors.convention);
      doc["to"] = location_convention_name(to);
      doc["workpiece_setup"] = parts_json(r.workpiece_setup);
      doc["tool_setup"] = parts_json(r.tool_setup);
      doc["check"] = {{"poses", r.check_poses},
                      {"tip_um", r.check_tip_mm * units::kUmPerMm},
                      {"axis_urad", r.check_axis_rad * units::kUradPerRad}};
      doc["output"] = o->output;
      report << doc.dump(2) << "\n";
      return 0;
    }
    if (same) {
      report << fmt::format(
          "{} already gives its location errors in the {} convention: written "
          "unchanged.\n",
          o->errors, o->to);
      return 0;
    }
    report << fmt::format(
        "Location errors converted from {} to {}.\n"
        "The link model is the ISO 230-1 model with the workpiece and the spindle set up "
        "differently (last frame of each chain):\n"
        "  workpiece: {}  (probe the part's origin and alignment again)\n"
        "  spindle:   {}  (measure the tool and the spindle's alignment again)\n"
        "Check: the two models with these set-up parts differ by at most {:.6f} µm at the tool "
        "tip and {:.6f} µrad in the tool axis over {} poses.\n",
        location_convention_name(errors.convention), location_convention_name(to),
        parts_text(r.workpiece_setup), parts_text(r.tool_setup), r.check_tip_mm * units::kUmPerMm,
        r.check_axis_rad * units::kUradPerRad, r.check_poses);
    if (o->output != "-") report << "Written: " << o->output << "\n";
    return 0;
  };
}

}  // namespace

static const CommandRegistration kConvert(63, register_convert);

}  // namespace volmap::cli
