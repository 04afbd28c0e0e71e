#include "maps/tables/node_uncertainty.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <stdexcept>
#include <vector>

#include "core/common/parallel.h"
#include "core/model/gain_evaluator.h"

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
        "{}: metadata \"# {}: {}\" is not a non-negative number (a standard uncertainty)", e.file,
        key, s));
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
  const std::size_t per_channel =
      table.channel_count() > 0
          ? table.values.size() / static_cast<std::size_t>(table.channel_count())
          : 0;
  table.channels.push_back("u");
  // Free first: the layout is empty, and the peak stays one table.
  std::vector<double>().swap(table.values);
  table.values.assign(per_channel * static_cast<std::size_t>(table.channel_count()), 0.0);
}

ParameterCovariance covariance_from_identify(const nlohmann::json& report, const Machine& m,
                                             Formulation f, const std::string& file) {
  std::string where = "";
  try {
    if (report.value("format", "") != "volmap-identify/1")
      throw std::invalid_argument("not a volmap-identify/1 report (`identify.json`)");
    where = "/parameters";
    std::map<std::string, std::pair<double, std::string>> sigma;  // name -> (std error, unit)
    const nlohmann::json& params = report.at("parameters");
    for (size_t i = 0; i < params.size(); ++i) {
      where = fmt::format("/parameters/{}", i);
      const nlohmann::json& p = params[i];
      if (p.at("status").get<std::string>() != "estimated") continue;
      const std::string name = p.at("name").get<std::string>();
      const std::string kind = p.at("kind").get<std::string>();
      if (kind == "component")
        throw std::invalid_argument(fmt::format(
            "{} is a component-curve parameter; only identified location errors are propagated "
            "(a report of identify without `identify.component` fits, or drop `covariance`)",
            name));
      if (kind != "location") continue;
      if (p.at("std_error").is_null())
        throw std::invalid_argument(
            fmt::format("{} has no standard error (no redundancy in the recording)", name));
      sigma[name] = {p.at("std_error").get<double>(), p.at("unit").get<std::string>()};
    }
    where = "/correlation";
    const std::vector<std::string> names =
        report.at("correlation").at("names").get<std::vector<std::string>>();
    const nlohmann::json& matrix = report.at("correlation").at("matrix");
    const GainEvaluator gains(m, f);
    ParameterCovariance c;
    std::vector<size_t> rows;
    for (size_t i = 0; i < names.size(); ++i) {
      const auto it = sigma.find(names[i]);
      if (it == sigma.end()) continue;  // a setup offset
      const int k = gains.index_of(names[i]);
      if (k < 0)
        throw std::invalid_argument(
            fmt::format("{} is not an error of machine {}", names[i], m.name));
      c.names.push_back(names[i]);
      c.gain_index.push_back(k);
      rows.push_back(i);
    }
    const Eigen::Index n = static_cast<Eigen::Index>(rows.size());
    c.covariance = Eigen::MatrixXd::Zero(n, n);
    for (Eigen::Index a = 0; a < n; ++a)
      for (Eigen::Index b = 0; b < n; ++b) {
        const auto& [sa, ua] = sigma.at(c.names[static_cast<size_t>(a)]);
        const auto& [sb, ub] = sigma.at(c.names[static_cast<size_t>(b)]);
        const double rho =
            matrix.at(rows[static_cast<size_t>(a)]).at(rows[static_cast<size_t>(b)]).get<double>();
        const double ka = ua == "urad" ? 1e-6 : 1e-3, kb = ub == "urad" ? 1e-6 : 1e-3;
        c.covariance(a, b) = rho * sa * ka * sb * kb;
      }
    return c;
  } catch (const nlohmann::json::exception& e) {
    throw std::invalid_argument(
        fmt::format("{}: {}: {}", file, where.empty() ? "/" : where, e.what()));
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(
        fmt::format("{}: {}: {}", file, where.empty() ? "/" : where, e.what()));
  }
}

void fill_uncertainty(const ErrorModel& model, VolumetricTable& table, const Repeatability& r,
                      int threads, const ParameterCovariance* covariance) {
  const std::optional<int> channel = table.channel("u");
  if (!channel) throw std::invalid_argument("fill_uncertainty: the table has no channel u");
  const ErrorSet& errors = model.errors();
  // sigma^2 per error of the model (0: not given in the file).
  const GainEvaluator probe(model.machine(), model.options().formulation, errors.convention);
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
  // The covariance replaces the repeatability of the errors it names.
  if (covariance != nullptr)
    for (int k : covariance->gain_index) variance[static_cast<std::size_t>(k)] = 0.0;
  const std::int64_t nodes = table.node_count();
  // Chunks of at least 1024 nodes, one per thread.
  const std::int64_t chunks =
      std::min<std::int64_t>(thread_count(threads), std::max<std::int64_t>(1, nodes / 1024));
  auto work = [&](std::int64_t first, std::int64_t last) {
    GainEvaluator gains(model.machine(), model.options().formulation, errors.convention);
    for (std::int64_t n = first; n < last; ++n) {
      gains.at(table.node_position(n));
      double sum = 0.0;
      for (std::size_t k = 0; k < variance.size(); ++k)
        if (variance[k] > 0.0) sum += variance[k] * gains.dP(static_cast<int>(k)).squaredNorm();
      if (covariance != nullptr) {
        const std::vector<int>& g = covariance->gain_index;
        for (size_t a = 0; a < g.size(); ++a)
          for (size_t b = 0; b < g.size(); ++b)
            sum +=
                covariance->covariance(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) *
                gains.dP(g[a]).dot(gains.dP(g[b]));
      }
      sum = std::max(sum, 0.0);
      const double u = std::sqrt(sum);
      for (int layer = 0; layer < table.layer_count(); ++layer) table.at(layer, n)[*channel] = u;
    }
  };
  parallel_for(chunks, static_cast<int>(chunks), [&](std::int64_t chunk, int) {
    work(nodes * chunk / chunks, nodes * (chunk + 1) / chunks);
  });
}

}  // namespace volmap::maps
