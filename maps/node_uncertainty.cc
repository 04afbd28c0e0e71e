#include "maps/node_uncertainty.h"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "core/gain_evaluator.h"

namespace volmap::maps {

namespace {

std::optional<double> metadata_number(const ErrorSet& e, const std::string& key) {
  const auto it = e.metadata.find(key);
  if (it == e.metadata.end()) return std::nullopt;
  const std::string& s = it->second;
  double v = 0.0;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size() || !(v >= 0.0) || !std::isfinite(v))
    throw std::invalid_argument(fmt::format(
        "{}: metadata \"# {}: {}\" is not a non-negative number (a standard uncertainty)", e.file, key, s));
  return v;
}

}  // namespace

std::optional<Repeatability> repeatability_from(const ErrorSet& errors) {
  const std::optional<double> um = metadata_number(errors, "repeatability_um");
  const std::optional<double> urad = metadata_number(errors, "repeatability_urad");
  if (!um && !urad) return std::nullopt;
  return Repeatability{um.value_or(0.0) * 1e-3, urad.value_or(0.0) * 1e-6};
}

void add_uncertainty_channel(VolumetricTable& table) {
  if (table.channel("u")) return;
  const std::size_t per_channel = table.channel_count() > 0 ? table.values.size() / static_cast<std::size_t>(table.channel_count()) : 0;
  table.channels.push_back("u");
  // Free first: the layout is empty, and the peak stays one table.
  std::vector<double>().swap(table.values);
  table.values.assign(per_channel * static_cast<std::size_t>(table.channel_count()), 0.0);
}

void fill_uncertainty(const ErrorModel& model, VolumetricTable& table, const Repeatability& r,
                      int threads) {
  const std::optional<int> channel = table.channel("u");
  if (!channel) throw std::invalid_argument("fill_uncertainty: the table has no channel u");
  const ErrorSet& errors = model.errors();
  // sigma^2 per error of the model (0: not given in the file).
  const GainEvaluator probe(model.machine(), model.options().formulation);
  std::vector<double> variance(probe.names().size(), 0.0);
  for (std::size_t k = 0; k < variance.size(); ++k) {
    const std::optional<ErrorName> n = parse_error_name(probe.names()[k]);
    if (!n) continue;
    bool given = false;
    if (n->location) {
      given = errors.location.count(error_name_string(*n)) > 0;
    } else if (const AxisErrors* a = errors.errors_of(n->axis)) {
      given = a->present[static_cast<std::size_t>(n->component)];
    }
    const double sigma = is_angular(n->component) ? r.angular_rad : r.translational_mm;
    if (given) variance[k] = sigma * sigma;
  }
  const std::int64_t nodes = table.node_count();
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  threads = static_cast<int>(std::min<std::int64_t>(threads, std::max<std::int64_t>(1, nodes / 1024)));
  auto work = [&](std::int64_t first, std::int64_t last) {
    GainEvaluator gains(model.machine(), model.options().formulation);
    for (std::int64_t n = first; n < last; ++n) {
      gains.at(table.node_position(n));
      double sum = 0.0;
      for (std::size_t k = 0; k < variance.size(); ++k)
        if (variance[k] > 0.0) sum += variance[k] * gains.dP(static_cast<int>(k)).squaredNorm();
      const double u = std::sqrt(sum);
      for (int layer = 0; layer < table.layer_count(); ++layer) table.at(layer, n)[*channel] = u;
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back(work, nodes * t / threads, nodes * (t + 1) / threads);
  for (std::thread& t : pool) t.join();
}

}  // namespace volmap::maps
