#include "cli/message_wording.h"

#include <cctype>

namespace volmap::cli {
namespace {

bool field_char(char c) {
  return std::islower(static_cast<unsigned char>(c)) ||
         std::isdigit(static_cast<unsigned char>(c)) || c == '_';
}

// "tolerance_um" -> "--tolerance-um".
std::string flag_of(const std::string& field) {
  std::string flag = "--" + field;
  for (char& c : flag)
    if (c == '_') c = '-';
  return flag;
}

// The command-line wording of one field ("clamp" of `verb`, or
// "verify.clamp"), or empty when no command has it.
std::string option_wording(const std::string& field, const CLI::App& app, const CLI::App* verb) {
  const size_t dot = field.find('.');
  if (dot == std::string::npos) {
    const std::string flag = flag_of(field);
    return verb && verb->get_option_no_throw(flag) ? flag : std::string();
  }
  const std::string command = field.substr(0, dot), flag = flag_of(field.substr(dot + 1));
  const auto named =
      app.get_subcommands([&](const CLI::App* sub) { return sub->get_name() == command; });
  if (named.empty() || !named.front()->get_option_no_throw(flag)) return {};
  return "volmap " + command + " " + flag;
}

}  // namespace

std::string flag_wording(const std::string& message, const CLI::App& app, const CLI::App* verb) {
  std::string out;
  out.reserve(message.size());
  size_t at = 0;
  while (at < message.size()) {
    const size_t open = message.find('`', at);
    if (open == std::string::npos) break;
    // A field: lower-case letters, digits and '_', at most one '.', and
    // starting with a letter.
    size_t end = open + 1;
    int dots = 0;
    while (end < message.size() && (field_char(message[end]) || (message[end] == '.' && !dots++)))
      ++end;
    const std::string field = message.substr(open + 1, end - open - 1);
    const bool is_field = end < message.size() && message[end] == '`' && !field.empty() &&
                          std::islower(static_cast<unsigned char>(field[0])) && field.back() != '.';
    const std::string wording = is_field ? option_wording(field, app, verb) : std::string();
    out.append(message, at, open - at);
    if (wording.empty()) {
      out += '`';
      at = open + 1;
    } else {
      out += wording;
      at = end + 1;
    }
  }
  out.append(message, at, std::string::npos);
  return out;
}

}  // namespace volmap::cli
