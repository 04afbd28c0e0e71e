#include "maps/tables/factorized_table.h"

#include <fmt/format.h>

#include <istream>
#include <sstream>

#include "core/common/input_error.h"
#include "core/model/machine_json.h"
#include "maps/tables/output_wording.h"

namespace volmap::maps {

namespace {

constexpr const char* kFormat = "volmap-factorized/1";

nlohmann::ordered_json table_json(const AxisErrorTable& t) {
  nlohmann::ordered_json j;
  j["position"] = t.position;
  nlohmann::ordered_json values = nlohmann::ordered_json::array();
  nlohmann::ordered_json slopes = nlohmann::ordered_json::array();
  for (size_t i = 0; i < t.position.size(); ++i) {
    values.push_back(t.value[i]);
    slopes.push_back(t.slope[i]);
  }
  j["value"] = std::move(values);
  j["slope"] = std::move(slopes);
  j["periodic"] = t.periodic;
  return j;
}

AxisErrorTable table_from(const nlohmann::ordered_json& j, AxisName axis,
                          const std::string& where) {
  AxisErrorTable t;
  t.axis = axis;
  t.source = where;
  t.position = j.at("position").get<std::vector<double>>();
  t.value = j.at("value").get<std::vector<std::array<double, kComponentCount>>>();
  t.slope = j.at("slope").get<std::vector<std::array<double, kComponentCount>>>();
  t.periodic = j.at("periodic").get<bool>();
  if (t.value.size() != t.position.size() || t.slope.size() != t.position.size() ||
      t.position.size() < 1)
    throw std::invalid_argument("position, value and slope differ in length");
  for (size_t i = 1; i < t.position.size(); ++i)
    if (!(t.position[i] > t.position[i - 1]))
      throw std::invalid_argument("positions are not strictly increasing");
  return t;
}

}  // namespace

FactorizedTable make_factorized(const nlohmann::ordered_json& machine_definition,
                                const ErrorModel& model) {
  FactorizedTable t;
  t.machine_definition = machine_definition;
  t.machine_name = model.machine().name;
  t.errors_source = model.errors().file;
  t.formulation = model.options().formulation;
  t.errors = model.errors();
  t.errors.metadata.clear();
  return t;
}

ErrorModel factorized_model(const FactorizedTable& t) {
  std::istringstream in(t.machine_definition.dump());
  Machine m = read_machine_json(in, t.machine_name + " (embedded in the factorized table)");
  ErrorSet e = t.errors;
  prepare_lookup(e);
  return ErrorModel(std::move(m), std::move(e), ModelOptions{t.formulation, OutsidePolicy::kError});
}

std::string factorized_json(const FactorizedTable& t) {
  nlohmann::ordered_json doc;
  doc["format"] = kFormat;
  doc["machine"] = t.machine_name;
  doc["errors"] = t.errors_source;
  doc["model"] = t.formulation == Formulation::kDependent ? "dependent" : "independent";
  doc["evaluation"] =
      "dv(u) = F_e(u) - F_f,n(u) through the HTM chain of machine_definition (docs/maps.md, "
      "Factorized form); component errors: cubic Hermite on each table's knots; units mm, rad";
  doc["machine_definition"] = t.machine_definition;
  nlohmann::ordered_json axes = nlohmann::ordered_json::array();
  for (const std::optional<AxisErrors>& a : t.errors.axis) {
    if (!a) continue;
    nlohmann::ordered_json j;
    j["axis"] = std::string(1, axis_char(a->axis));
    j["present"] = a->present;
    j["plus"] = table_json(a->plus);
    if (a->bidirectional()) j["minus"] = table_json(a->minus);
    axes.push_back(std::move(j));
  }
  doc["component_errors"] = std::move(axes);
  doc["location_errors"] = t.errors.location;
  doc["location_convention"] = location_convention_name(t.errors.convention);
  return doc.dump(1) + "\n";
}

void save_factorized(const std::string& path, const FactorizedTable& t) {
  AtomicOutput file(path, {}, kOutputWording);
  file.stream() << factorized_json(t);
  file.commit();
}

FactorizedTable read_factorized(std::istream& in, const std::string& file) {
  nlohmann::ordered_json doc;
  try {
    doc = nlohmann::ordered_json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(file, 0, fmt::format("not JSON ({})", e.what()));
  }
  std::string where = "/";
  try {
    if (!doc.is_object() || doc.value("format", "") != kFormat)
      throw std::invalid_argument(fmt::format("not a {} document", kFormat));
    FactorizedTable t;
    where = "/machine_definition";
    t.machine_definition = doc.at("machine_definition");
    t.machine_name = doc.at("machine").get<std::string>();
    t.errors_source = doc.at("errors").get<std::string>();
    const std::string model = doc.at("model").get<std::string>();
    if (model != "dependent" && model != "independent")
      throw std::invalid_argument("model is neither dependent nor independent");
    t.formulation = model == "dependent" ? Formulation::kDependent : Formulation::kIndependent;
    t.errors.file = t.errors_source;
    const nlohmann::ordered_json& axes = doc.at("component_errors");
    for (size_t i = 0; i < axes.size(); ++i) {
      where = fmt::format("/component_errors/{}", i);
      const std::string letter = axes[i].at("axis").get<std::string>();
      const std::optional<AxisName> a =
          letter.size() == 1 ? axis_from_char(letter[0]) : std::nullopt;
      if (!a) throw std::invalid_argument(fmt::format("axis \"{}\" is not X Y Z A B C", letter));
      AxisErrors e;
      e.axis = *a;
      e.present = axes[i].at("present").get<std::array<bool, kComponentCount>>();
      e.plus = table_from(axes[i].at("plus"), *a, file + where + "/plus");
      if (axes[i].contains("minus"))
        e.minus = table_from(axes[i].at("minus"), *a, file + where + "/minus");
      t.errors.axis[static_cast<size_t>(*a)] = std::move(e);
    }
    where = "/location_errors";
    t.errors.location = doc.at("location_errors").get<std::map<std::string, double>>();
    // Written since the location errors mean ISO 230-1 (2026-12-03); a file
    // without it was written when they meant link errors.
    where = "/location_convention";
    t.errors.convention = LocationConvention::kLink;
    if (doc.contains("location_convention")) {
      const std::optional<LocationConvention> c =
          parse_location_convention(doc.at("location_convention").get<std::string>());
      if (!c) throw std::invalid_argument("location_convention is neither iso230-1 nor link");
      t.errors.convention = *c;
    }
    where = "/machine_definition";
    (void)factorized_model(t);  // validates the machine and binds the errors
    return t;
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError::at_json_path(
        file, where, fmt::format("{}; write it again with `map.form` factorized", e.what()));
  }
}

std::size_t factorized_values(const FactorizedTable& t) {
  std::size_t n = t.errors.location.size();
  for (const std::optional<AxisErrors>& a : t.errors.axis) {
    if (!a) continue;
    n += a->plus.position.size() * (1 + 2 * kComponentCount);
    n += a->minus.position.size() * (1 + 2 * kComponentCount);
  }
  return n;
}

}  // namespace volmap::maps
