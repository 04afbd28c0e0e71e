// csv and json exports: every node of every direction layer (docs/exports.md).
#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "maps/exports/exporters.h"
#include "maps/tables/layer_name.h"

namespace volmap::maps::exporters {

namespace {

std::string position_column(AxisName a) {
  const char c = static_cast<char>(axis_char(a) - 'A' + 'a');
  return fmt::format("{}_{}", c, is_rotary(a) ? "deg" : "mm");
}
// Degrees rounded to 1e-9 deg (the rad round trip of 30 deg gives
// 29.999999999999996).
double display(AxisName a, double v) {
  return is_rotary(a) ? std::round(v * 180.0 / M_PI * 1e9) / 1e9 + 0.0 : v;
}

// Channel names with display units: lengths in um, angles / unit vectors in urad.
std::string value_column(const std::string& channel) {
  return channel + (is_angular_channel(channel) ? "_urad" : "_um");
}

}  // namespace

std::vector<ExportFile> csv(const VolumetricTable& t, const ExportOptions&) {
  std::vector<ExportFile> files;
  std::string header;
  for (const GridAxis& g : t.grid) header += position_column(g.axis) + ",";
  for (int c = 0; c < t.channel_count(); ++c)
    header +=
        value_column(t.channels[static_cast<size_t>(c)]) + (c + 1 < t.channel_count() ? "," : "\n");
  const std::int64_t nodes = t.node_count();
  std::vector<std::int64_t> idx(static_cast<size_t>(t.axis_count()));
  for (int layer = 0; layer < t.layer_count(); ++layer) {
    ExportFile f;
    const std::string tag = layer_label(t, layer, "_", "pos", "neg");
    f.name = tag.empty() ? "table.csv" : "table_" + tag + ".csv";
    f.text.reserve(static_cast<size_t>(nodes) * 16 *
                   static_cast<size_t>(t.axis_count() + t.channel_count()));
    f.text += header;
    for (std::int64_t n = 0; n < nodes; ++n) {
      t.node_index(n, idx.data());
      for (int d = 0; d < t.axis_count(); ++d) {
        const GridAxis& g = t.grid[static_cast<size_t>(d)];
        f.text += fixed(display(g.axis, g.node(idx[static_cast<size_t>(d)])), 4);
        f.text += ',';
      }
      const double* v = t.at(layer, n);
      for (int c = 0; c < t.channel_count(); ++c) {
        f.text +=
            fixed(v[c] * (is_angular_channel(t.channels[static_cast<size_t>(c)]) ? 1e6 : 1e3), 6);
        f.text += c + 1 < t.channel_count() ? ',' : '\n';
      }
    }
    files.push_back(std::move(f));
  }
  return files;
}

std::vector<ExportFile> json(const VolumetricTable& t, const ExportOptions&) {
  nlohmann::ordered_json doc;
  doc["format"] = "volmap-table-export/1";
  doc["machine"] = t.machine_name;
  doc["errors"] = t.errors_source;
  doc["model"] = t.formulation == Formulation::kDependent ? "dependent" : "independent";
  doc["sign"] =
      "e*: tool-tip error, actual minus nominal, workpiece coordinates; "
      "u*: commanded-position correction x_cmd - x_nominal";
  nlohmann::ordered_json grid = nlohmann::ordered_json::array();
  for (const GridAxis& g : t.grid)
    grid.push_back({{"axis", std::string(1, axis_char(g.axis))},
                    {"unit", is_rotary(g.axis) ? "deg" : "mm"},
                    {"start", display(g.axis, g.start)},
                    {"spacing", display(g.axis, g.spacing)},
                    {"end", display(g.axis, g.end)},
                    {"nodes", g.count}});
  doc["grid"] = grid;
  doc["order"] = "node index i0 + n0 * (i1 + n1 * (i2 + ...)): first axis fastest";
  nlohmann::ordered_json layers = nlohmann::ordered_json::array();
  for (int layer = 0; layer < t.layer_count(); ++layer) {
    nlohmann::ordered_json l;
    nlohmann::ordered_json dirs = nlohmann::ordered_json::object();
    const ApproachDirections d = t.layer_directions(layer);
    for (int a : t.bidirectional_axes)
      dirs[std::string(1, axis_char(t.grid[static_cast<size_t>(a)].axis))] =
          d[static_cast<size_t>(a)] > 0 ? "+" : "-";
    l["directions"] = dirs;
    for (int c = 0; c < t.channel_count(); ++c) {
      const std::string& name = t.channels[static_cast<size_t>(c)];
      const double k = is_angular_channel(name) ? 1e6 : 1e3;
      nlohmann::ordered_json values = nlohmann::ordered_json::array();
      for (std::int64_t n = 0; n < t.node_count(); ++n) {
        // Round to 1e-6 um (1 fm): the file is for people and tools, the
        // binary table keeps every bit.
        values.push_back(std::round(t.at(layer, n)[c] * k * 1e6) / 1e6 + 0.0);
      }
      l[value_column(name)] = std::move(values);
    }
    layers.push_back(std::move(l));
  }
  doc["layers"] = std::move(layers);
  return {{"table.json", doc.dump(1) + "\n"}};
}

}  // namespace volmap::maps::exporters
