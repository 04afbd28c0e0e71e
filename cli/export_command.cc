// volmap export: writes a table file (volmap map) in a format for people or
// a controller (docs/exports.md) into a folder.
#include <fmt/format.h>

#include <algorithm>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "cli/commands.h"
#include "maps/exports/export_inputs.h"
#include "maps/exports/exporters.h"
#include "maps/tables/output_wording.h"
#include "maps/tables/table_file.h"

namespace volmap::cli {

namespace {

Runner register_export(CLI::App& app) {
  struct Opts {
    std::string table, format, output, machine, errors, errors_format = "auto";
    double detection_unit_um = 1.0, input_increment_um = 1.0;
    std::string fanuc_series = "30i", reference_direction = "+";
    std::vector<std::string> param_3605;
    bool json = false;
  };
  auto o = std::make_shared<Opts>();
  std::string formats;
  for (const std::string& f : maps::export_formats()) formats += (formats.empty() ? "" : ", ") + f;
  CLI::App* sub = app.add_subcommand(
      "export", "Writes a table (volmap map) for people or a controller (docs/exports.md)");
  sub->add_option("--table", o->table, "Table file written by volmap map")->required();
  sub->add_option("--format", o->format, "Format: " + formats)->required();
  sub->add_option("-o,--output", o->output,
                  "Folder to write the files into (created when missing); - writes an export "
                  "of one file to standard output")
      ->required();
  sub->add_option("--machine", o->machine,
                  "Machine definition: its home position picks the line of one-dimensional "
                  "controller tables (default: each axis's travel start)");
  sub->add_option(
      "--errors", o->errors,
      "The errors the table was built from (errors.md CSV, ISG CSV or Etalon): needed by "
      "isg-csv and by the KinematicsComp tables of heidenhain; default the errors file the table "
      "names, when it exists");
  sub->add_option("--errors-format", o->errors_format,
                  "Format of --errors: auto (default: detected), volmap (errors.md), isg-csv "
                  "(Beckhoff/ISG CSV), etalon (Etalon exchange format, Vendor variant)")
      ->check(CLI::IsMember({"auto", "volmap", "isg-csv", "etalon"}));
  sub->add_option("--detection-unit-um", o->detection_unit_um,
                  "fanuc: detection unit of the axes, µm (default 1); compensation values are "
                  "integers in it")
      ->check(CLI::PositiveNumber);
  sub->add_option("--fanuc-series", o->fanuc_series,
                  "fanuc: the control's series, which sets the limits, units and record form: "
                  "30i (default; also 31i, 32i, 0i-F) or 16i (also 18i, 21i, 0i-A..0i-D)");
  sub->add_option("--fanuc-param-3605", o->param_3605,
                  "fanuc: parameter 3605 as the control shows it (8 binary digits, bit 7 first), "
                  "once or per axis (comma-separated); bit 0 is set from the table, the others "
                  "kept. Without it 3605 is not written (FANUC.txt says which bit to set)")
      ->delimiter(',');
  sub->add_option("--fanuc-reference-direction", o->reference_direction,
                  "fanuc: reference position return direction, + (1006#5 ZMI = 0, default) or -")
      ->check(CLI::IsMember({"+", "-"}));
  sub->add_option("--input-increment-um", o->input_increment_um,
                  "fanuc, 16i series: least input increment, µm (default 1), the unit of 3624")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--json", o->json, "Write the list of files as one JSON document to stdout");
  sub->footer(
      "Example:\n  volmap export --table hsu.vmt --format linuxcnc -o hsu-linuxcnc/\n"
      "  volmap export --table hsu.vmt --format heidenhain --errors samples/errors/hsu-3axis.csv "
      "-o tnc/");

  return [o, formats]() -> int {
    const auto& known = maps::export_formats();
    if (std::find(known.begin(), known.end(), o->format) == known.end())
      throw UsageError(
          fmt::format("--format {}: unknown format; the formats are {}", o->format, formats));
    refuse_output_equal_to_input(o->output, {o->table, o->machine, o->errors},
                                 maps::kOutputWording);
    const maps::VolumetricTable table = maps::load_table(o->table);
    maps::ExportOptions options;
    if (!o->machine.empty()) options.home = maps::export_home(o->machine, table, o->table);
    options.detection_unit_mm = o->detection_unit_um * 1e-3;
    try {
      options.fanuc.series = maps::parse_fanuc_series(o->fanuc_series);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--fanuc-series: ") + e.what());
    }
    options.fanuc.param_3605 = o->param_3605;
    options.fanuc.reference_direction = o->reference_direction == "-" ? -1 : +1;
    options.fanuc.input_increment_mm = o->input_increment_um * 1e-3;
    const std::optional<ErrorSet> errors =
        maps::export_errors(table, o->errors, parse_errors_format(o->errors_format), o->table,
                            o->format == "heidenhain" || o->format == "isg-csv");
    if (errors) options.errors = &*errors;
    std::vector<maps::ExportFile> files;
    try {
      files = maps::export_table(table, o->format, options);
    } catch (const maps::ExportError& e) {
      throw std::invalid_argument(fmt::format("{}: {}", o->table, e.what()));
    }
    if (o->output == "-") {
      // -o - writes standard output (cli.md): an export of one file only.
      if (files.size() != 1) {
        std::string names;
        for (const maps::ExportFile& f : files) names += (names.empty() ? "" : ", ") + f.name;
        throw UsageError(fmt::format(
            "-o -: the {} export writes {} files ({}); standard output takes one: give a folder",
            o->format, files.size(), names));
      }
      if (o->json)
        throw UsageError("-o -: the export goes to standard output; --json would mix with it");
      std::cout << files.front().text;
      return 0;
    }
    maps::write_export(o->output, files);
    if (o->json) {
      nlohmann::ordered_json doc;
      doc["format"] = o->format;
      doc["folder"] = o->output;
      nlohmann::ordered_json list = nlohmann::ordered_json::array();
      for (const maps::ExportFile& f : files)
        list.push_back({{"name", f.name}, {"bytes", f.text.size()}});
      doc["files"] = list;
      std::cout << doc.dump(2) << "\n";
      return 0;
    }
    std::cout << fmt::format("Exported {} ({}) as {} into {}:\n", o->table, table.machine_name,
                             o->format, o->output);
    for (const maps::ExportFile& f : files)
      std::cout << fmt::format("  {}  ({} bytes)\n", f.name, f.text.size());
    return 0;
  };
}

}  // namespace

static const CommandRegistration kExport(41, register_export);

}  // namespace volmap::cli
