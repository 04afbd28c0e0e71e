#include "maps/exports/export_inputs.h"

#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>

#include "core/model/machine_json.h"

namespace volmap::maps {

namespace {
std::optional<ErrorSet> find_errors(const VolumetricTable& table, const std::string& errors_path,
                                    ErrorsFormat format, const std::string& table_path,
                                    bool needed);
}  // namespace

std::vector<double> export_home(const std::string& machine_path, const VolumetricTable& table,
                                const std::string& table_path) {
  const Machine m = load_machine_json(machine_path);
  if (m.axis_count() != table.axis_count())
    throw std::invalid_argument(fmt::format("{}: machine {} has {} axes, the table {} has {}",
                                            machine_path, m.name, m.axis_count(), table_path,
                                            table.axis_count()));
  std::vector<double> home;
  for (int i = 0; i < m.axis_count(); ++i) home.push_back(m.home[i]);
  return home;
}

std::optional<ErrorSet> export_errors(const VolumetricTable& table, const std::string& errors_path,
                                      ErrorsFormat format, const std::string& table_path,
                                      bool needed) {
  std::optional<ErrorSet> e = find_errors(table, errors_path, format, table_path, needed);
  // The controllers take location errors as ISO 230-1 defines them
  // (docs/exports.md); a link-convention file is converted first, with its
  // machine, by volmap convert.
  if (e && needed && e->convention == LocationConvention::kLink && !e->location.empty())
    throw std::invalid_argument(fmt::format(
        "{}: its location errors are in the link convention, and the controller takes them as "
        "ISO 230-1 defines them; convert the file (volmap convert --machine M.json --errors {} "
        "--to iso230-1 -o iso.csv), build the table again from it (volmap map), and export that",
        e->file, e->file));
  return e;
}

namespace {
std::optional<ErrorSet> find_errors(const VolumetricTable& table, const std::string& errors_path,
                                    ErrorsFormat format, const std::string& table_path,
                                    bool needed) {
  if (!errors_path.empty()) return load_errors(errors_path, format);
  // The table names the errors file it was built from (as given to volmap
  // map): formats that export the component errors themselves (isg-csv,
  // HEIDENHAIN KinematicsComp) read it from there when no errors file is
  // given, so `export --table T --format F -o DIR` works as cli.md writes
  // it. A given errors file overrides.
  if (table.errors_source.empty() || table.errors_source == "-") return std::nullopt;
  namespace fs = std::filesystem;
  const fs::path named(table.errors_source);
  std::vector<fs::path> places{named};
  if (named.is_relative()) places.push_back(fs::path(table_path).parent_path() / named);
  for (const fs::path& p : places)
    if (fs::is_regular_file(p)) return load_errors(p.string(), ErrorsFormat::kAuto);
  if (needed)
    throw std::invalid_argument(fmt::format(
        "{}: the table was built from the errors file '{}', found neither from the current folder "
        "nor beside the table; give it with `errors` E.csv",
        table_path, table.errors_source));
  return std::nullopt;
}
}  // namespace

}  // namespace volmap::maps
