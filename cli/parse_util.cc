#include "cli/parse_util.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "cli/commands.h"
#include "core/model/errors_machine.h"

namespace volmap::cli {

std::vector<double> parse_numbers(const std::string& text, const std::string& option) {
  std::vector<double> values;
  size_t start = 0;
  while (true) {
    const size_t comma = text.find(',', start);
    std::string cell =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
    while (!cell.empty() && cell.back() == ' ') cell.pop_back();
    if (!cell.empty() && cell.front() == '+') cell.erase(cell.begin());
    double v = 0;
    const auto res = std::from_chars(cell.data(), cell.data() + cell.size(), v);
    if (cell.empty() || res.ec != std::errc() || res.ptr != cell.data() + cell.size() ||
        !std::isfinite(v))
      throw UsageError(fmt::format("{} {}: \"{}\" is not a number", option, text, cell));
    values.push_back(v);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return values;
}

AxisVector parse_axis_position(const Machine& m, const std::string& text,
                               const std::string& option) {
  const std::vector<double> values = parse_numbers(text, option);
  std::string order;
  for (AxisName a : m.axis_order) order += std::string(order.empty() ? "" : ",") + axis_char(a);
  if (static_cast<int>(values.size()) != m.axis_count())
    throw UsageError(fmt::format("{} {}: expected {} values ({}), got {}", option, text,
                                 m.axis_count(), order, values.size()));
  AxisVector u(m.axis_count());
  for (int i = 0; i < m.axis_count(); ++i)
    u[i] = values[static_cast<size_t>(i)] *
           (is_rotary(m.axis_order[static_cast<size_t>(i)]) ? M_PI / 180.0 : 1.0);
  try {
    check_within_travel(m, u);
  } catch (const std::invalid_argument& e) {
    throw UsageError(fmt::format("{} {}: {}", option, text, e.what()));
  }
  return u;
}

double display_position(AxisName a, double value) {
  return is_rotary(a) ? value * 180.0 / M_PI : value;
}

void add_other_machine_flag(CLI::App& sub, bool& flag) {
  sub.add_flag(kOtherMachineErrors, flag,
               "Use errors whose '# machine:' line names another machine (default: refuse, "
               "since errors of another machine give a wrong correction)");
}

ErrorSet load_errors_for(const Machine& m, const std::string& machine_path,
                         const std::string& errors_path, ErrorsFormat format, bool other_machine) {
  ErrorSet e = load_errors(errors_path, format);
  if (!other_machine) require_errors_of_machine(e, m, machine_path, kOtherMachineErrors);
  return e;
}

}  // namespace volmap::cli
