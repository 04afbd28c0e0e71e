#include "maps/tables/volumetric_table.h"

#include <fmt/format.h>

#include <array>
#include <cassert>
#include <cmath>
#include <stdexcept>

#include "core/common/internal_error.h"
#include "core/kinematics/kinematics.h"

namespace volmap::maps {

const char* interpolation_name(Interpolation m) {
  return m == Interpolation::kCubic ? "cubic" : "linear";
}

Interpolation parse_interpolation(const std::string& name) {
  if (name == "linear") return Interpolation::kLinear;
  if (name == "cubic") return Interpolation::kCubic;
  throw std::invalid_argument(fmt::format("interpolation \"{}\": expected linear or cubic", name));
}

std::int64_t VolumetricTable::node_count() const {
  std::int64_t n = 1;
  for (const GridAxis& g : grid) n *= g.count;
  return n;
}

std::optional<int> VolumetricTable::channel(const std::string& name) const {
  for (size_t c = 0; c < channels.size(); ++c)
    if (channels[c] == name) return static_cast<int>(c);
  return std::nullopt;
}

ApproachDirections VolumetricTable::layer_directions(int layer) const {
  ApproachDirections d{};
  for (size_t j = 0; j < bidirectional_axes.size(); ++j)
    d[static_cast<size_t>(bidirectional_axes[j])] = (layer >> j) & 1 ? -1 : +1;
  return d;
}

int VolumetricTable::layer_of(const ApproachDirections& dir) const {
  int layer = 0;
  for (size_t j = 0; j < bidirectional_axes.size(); ++j)
    if (dir[static_cast<size_t>(bidirectional_axes[j])] < 0) layer |= 1 << j;
  return layer;
}

void VolumetricTable::node_index(std::int64_t node, std::int64_t* index) const {
  for (size_t d = 0; d < grid.size(); ++d) {
    index[d] = node % grid[d].count;
    node /= grid[d].count;
  }
}

AxisVector VolumetricTable::node_position(std::int64_t node) const {
  AxisVector u(axis_count());
  for (size_t d = 0; d < grid.size(); ++d) {
    u[static_cast<int>(d)] = grid[d].node(node % grid[d].count);
    node /= grid[d].count;
  }
  return u;
}

bool VolumetricTable::three_axis_correction() const {
  if (axis_count() != 3 || !channel("ux")) return false;
  for (const GridAxis& g : grid)
    if (is_rotary(g.axis)) return false;
  return true;
}

bool VolumetricTable::pose_correction() const {
  if (grid.empty() || three_axis_correction()) return false;
  bool rotary = false;
  for (const GridAxis& g : grid) {
    rotary |= is_rotary(g.axis);
    if (!channel(correction_channel_name(g.axis))) return false;
  }
  return rotary;
}

int VolumetricTable::correction_channel() const {
  if (grid.empty()) return -1;
  const std::optional<int> c = channel(correction_channel_name(grid.front().axis));
  return c ? *c : -1;
}

std::string correction_channel_name(AxisName a) {
  return std::string("u") + static_cast<char>(axis_char(a) - 'A' + 'a');
}

bool is_angular_channel(const std::string& name) {
  if (name.size() != 2) return false;
  if (name[0] == 'e') return name[1] == 'i' || name[1] == 'j' || name[1] == 'k';
  if (name[0] == 'u') return name[1] == 'a' || name[1] == 'b' || name[1] == 'c';
  return false;
}

std::vector<std::string> channels_for(const Machine& m) {
  if (m.axis_count() == 3 && !m.has_rotary_axes()) return {"ex", "ey", "ez", "ux", "uy", "uz"};
  std::vector<std::string> c = {"ex", "ey", "ez", "ei", "ej", "ek"};
  bool invertible = true;
  try {
    const Kinematics kin(m);
    invertible = kin.has_rotary_axes();
  } catch (const std::invalid_argument&) {
    invertible = false;
  }
  if (invertible)
    for (AxisName a : m.axis_order) c.push_back(correction_channel_name(a));
  return c;
}

namespace {

std::vector<GridAxis> layout_grid(const Machine& m, const std::vector<double>& spacing) {
  if (static_cast<int>(spacing.size()) != m.axis_count())
    throw std::invalid_argument(
        fmt::format("expected {} spacings (one per axis), got {}", m.axis_count(), spacing.size()));
  std::vector<GridAxis> grid;
  for (int i = 0; i < m.axis_count(); ++i) {
    try {
      grid.push_back(make_grid_axis(m, i, spacing[static_cast<size_t>(i)]));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(
          fmt::format("axis {}: {}", axis_char(m.axis_order[static_cast<size_t>(i)]), e.what()));
    }
  }
  return grid;
}

int bidirectional_count(const ErrorModel& model) {
  int b = 0;
  for (AxisName a : model.machine().axis_order) {
    const AxisErrors* e = model.errors().errors_of(a);
    b += e != nullptr && e->bidirectional();
  }
  return b;
}

}  // namespace

std::size_t table_bytes(const ErrorModel& model, const std::vector<double>& spacing,
                        int extra_channels) {
  const std::vector<GridAxis> grid = layout_grid(model.machine(), spacing);
  const double nodes = static_cast<double>(total_nodes(grid));
  const double channels =
      static_cast<double>(channels_for(model.machine()).size()) + extra_channels;
  const double bytes =
      nodes * channels * static_cast<double>(1 << bidirectional_count(model)) * 8.0;
  return bytes > 1e18 ? static_cast<std::size_t>(1e18) : static_cast<std::size_t>(bytes);
}

VolumetricTable make_table_layout(const ErrorModel& model, const std::vector<double>& spacing,
                                  std::size_t max_bytes, int extra_channels) {
  const Machine& m = model.machine();
  if (static_cast<int>(spacing.size()) != m.axis_count())
    throw std::invalid_argument(
        fmt::format("expected {} spacings (one per axis), got {}", m.axis_count(), spacing.size()));
  VolumetricTable t;
  t.machine_name = m.name;
  t.errors_source = model.errors().file;
  t.formulation = model.options().formulation;
  t.grid = layout_grid(m, spacing);
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisErrors* e = model.errors().errors_of(m.axis_order[static_cast<size_t>(i)]);
    if (e != nullptr && e->bidirectional()) t.bidirectional_axes.push_back(i);
  }
  t.channels = channels_for(m);
  const std::size_t bytes = table_bytes(model, spacing, extra_channels);
  if (bytes > max_bytes) {
    std::string grid;
    for (const GridAxis& g : t.grid)
      grid += fmt::format("{}{}", grid.empty() ? "" : " x ", g.count);
    throw TableTooLarge(fmt::format(
        "the table would take {:.2f} GiB ({} nodes, {} layer{}, {} channels), more than the cap "
        "of {:.2f} GiB; give a coarser `spacing`",
        static_cast<double>(bytes) / (1 << 30), grid, t.layer_count(),
        t.layer_count() > 1 ? "s" : "", t.channel_count() + extra_channels,
        static_cast<double>(max_bytes) / (1 << 30)));
  }
  const std::int64_t count = total_nodes(t.grid) * t.layer_count() * t.channel_count();
  t.values.assign(static_cast<size_t>(count), 0.0);
  return t;
}

namespace {

constexpr int kMaxAxes = 6;

// One axis's share of an interpolation: up to four node indices and weights.
struct AxisWeights {
  std::array<std::int64_t, 4> index{};
  std::array<double, 4> weight{};
  int n = 0;
};

// Brings q into the grid (wrap, clamp, or throw). Returns true when clamped.
bool bring_inside(const GridAxis& g, double& q, OutsidePolicy outside) {
  if (q >= g.start && q <= g.end) return false;
  if (g.periodic && std::isfinite(q)) {
    const double period = g.end - g.start;
    q = g.start + std::fmod(q - g.start, period);
    if (q < g.start) q += period;
    if (q > g.end) q = g.end;
    return false;
  }
  if (outside == OutsidePolicy::kError || std::isnan(q)) {
    const double k = is_rotary(g.axis) ? 180.0 / M_PI : 1.0;
    const char* unit = is_rotary(g.axis) ? "deg" : "mm";
    throw OutsideTable(fmt::format("{}={:g} {} is outside the table's grid {:g}..{:g} {}",
                                   axis_char(g.axis), q * k, unit, g.start * k, g.end * k, unit));
  }
  q = q < g.start ? g.start : g.end;
  return true;
}

void linear_weights(const GridAxis& g, double q, AxisWeights& w) {
  std::int64_t i;
  double s;
  g.locate(q, i, s);
  w.n = 2;
  w.index = {i, i + 1, 0, 0};
  w.weight = {1.0 - s, s, 0.0, 0.0};
}

// 1-D cubic Hermite on [x_i, x_i+1] with slopes m_i = (y_i+1 - y_i-1) /
// (x_i+1 - x_i-1) (one-sided secant at a non-periodic end), written as
// weights of the four nodes i-1 .. i+2.
void cubic_weights(const GridAxis& g, double q, AxisWeights& w) {
  std::int64_t i;
  double s;
  g.locate(q, i, s);
  const std::int64_t n = g.count;
  const double period = g.end - g.start;
  const double x0 = g.node(i), x1 = g.node(i + 1);
  const double h = x1 - x0;
  const double t = 1.0 - s;
  const double h00 = (1.0 + 2.0 * s) * t * t;
  const double h01 = s * s * (3.0 - 2.0 * s);
  const double h10 = s * t * t * h;          // times m_i
  const double h11 = s * s * (s - 1.0) * h;  // times m_i+1
  // Neighbours: index and position of node i-1 and i+2 (across the wrap for
  // a periodic axis), or none at a non-periodic end.
  bool has_prev = i > 0, has_next = i + 2 < n;
  std::int64_t ip = i - 1, in = i + 2;
  double xp = has_prev ? g.node(i - 1) : 0.0, xn = has_next ? g.node(i + 2) : 0.0;
  if (g.periodic && n > 2) {
    if (!has_prev) {
      has_prev = true;
      ip = n - 2;
      xp = g.node(n - 2) - period;
    }
    if (!has_next) {
      has_next = true;
      in = 1;
      xn = g.node(1) + period;
    }
  }
  w.n = 4;
  w.index = {has_prev ? ip : i, i, i + 1, has_next ? in : i + 1};
  w.weight = {0.0, h00, h01, 0.0};
  if (has_prev) {  // m_i = (y1 - yp) / (x1 - xp)
    const double k = h10 / (x1 - xp);
    w.weight[2] += k;
    w.weight[0] -= k;
  } else {  // m_i = (y1 - y0) / h
    w.weight[2] += h10 / h;
    w.weight[1] -= h10 / h;
  }
  if (has_next) {  // m_i+1 = (yn - y0) / (xn - x0)
    const double k = h11 / (xn - x0);
    w.weight[3] += k;
    w.weight[1] -= k;
  } else {
    w.weight[2] += h11 / h;
    w.weight[1] -= h11 / h;
  }
}

}  // namespace

void interpolate(const VolumetricTable& t, const AxisVector& u, int layer, Interpolation method,
                 OutsidePolicy outside, double* out, std::uint64_t* clamped) {
  const int dims = t.axis_count();
  assert(dims <= kMaxAxes && u.size() == dims);
  assert(layer >= 0 && layer < t.layer_count());
  std::array<AxisWeights, kMaxAxes> w;
  std::array<std::int64_t, kMaxAxes> stride{};
  bool was_clamped = false;
  std::int64_t st = 1;
  for (int d = 0; d < dims; ++d) {
    const GridAxis& g = t.grid[static_cast<size_t>(d)];
    double q = u[d];
    was_clamped |= bring_inside(g, q, outside);
    if (method == Interpolation::kCubic)
      cubic_weights(g, q, w[static_cast<size_t>(d)]);
    else
      linear_weights(g, q, w[static_cast<size_t>(d)]);
    stride[static_cast<size_t>(d)] = st;
    st *= g.count;
  }
  if (was_clamped && clamped != nullptr) ++*clamped;

  const int channels = t.channel_count();
  for (int c = 0; c < channels; ++c) out[c] = 0.0;
  const double* base = t.at(layer, 0);
  // Odometer over the tensor product of the axes' nodes.
  std::array<int, kMaxAxes> k{};
  while (true) {
    double weight = 1.0;
    std::int64_t node = 0;
    for (int d = 0; d < dims; ++d) {
      const AxisWeights& a = w[static_cast<size_t>(d)];
      weight *= a.weight[static_cast<size_t>(k[static_cast<size_t>(d)])];
      node +=
          a.index[static_cast<size_t>(k[static_cast<size_t>(d)])] * stride[static_cast<size_t>(d)];
    }
    if (weight != 0.0) {
      const double* v = base + node * channels;
      for (int c = 0; c < channels; ++c) out[c] += weight * v[c];
    }
    int d = 0;
    for (; d < dims; ++d) {
      if (++k[static_cast<size_t>(d)] < w[static_cast<size_t>(d)].n) break;
      k[static_cast<size_t>(d)] = 0;
    }
    if (d == dims) break;
  }
}

}  // namespace volmap::maps
