#include "cli/message_wording.h"

#include <algorithm>
#include <cctype>
#include <regex>
#include <vector>

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

namespace {

// Levenshtein distance (insertions, deletions, substitutions).
size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// The candidate nearest `word`, if near enough to be a slip ("" if none).
std::string nearest(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_d = std::max<size_t>(2, word.size() / 3) + 1;
  for (const std::string& c : candidates) {
    const size_t d = edit_distance(word, c);
    if (d < best_d) best_d = d, best = c;
  }
  return best;
}

}  // namespace

std::string misspelling_hint(const CLI::App& app, int argc, const char* const* argv) {
  if (argc < 2 || argv[1][0] == '-') return {};
  const std::string command = argv[1];
  const CLI::App* verb = nullptr;
  std::vector<std::string> commands;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; })) {
    commands.push_back(sub->get_name());
    if (sub->get_name() == command) verb = sub;
  }
  if (!verb) {
    const std::string near = nearest(command, commands);
    return "'" + command + "' is not a volmap command" +
           (near.empty() ? std::string() : "; did you mean '" + near + "'?");
  }
  std::vector<std::string> options;
  for (const CLI::Option* o : verb->get_options())
    for (const std::string& n : o->get_lnames()) options.push_back("--" + n);
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0 || arg == "--") continue;
    const std::string name = arg.substr(0, arg.find('='));
    if (std::find(options.begin(), options.end(), name) != options.end()) continue;
    const std::string near = nearest(name, options);
    return "unknown option " + name + " of volmap " + command +
           (near.empty() ? std::string() : "; did you mean " + near + "?");
  }
  return {};
}

std::string flag_value_hint(const CLI::App& app, int argc, const char* const* argv,
                            const std::string& extras) {
  if (argc < 4) return {};
  const CLI::App* verb = nullptr;
  for (const CLI::App* sub : app.get_subcommands([](const CLI::App*) { return true; }))
    if (sub->get_name() == argv[1]) verb = sub;
  if (!verb) return {};
  // Unless the parser found the word extra, it may be the command's input
  // (post --json IN): only a command without positional input is sure.
  if (extras.empty())
    for (const CLI::Option* o : verb->get_options())
      if (o->get_positional()) return {};
  for (int i = 2; i + 1 < argc; ++i) {
    const std::string arg = argv[i], next = argv[i + 1];
    if (arg.rfind("--", 0) != 0 || arg.find('=') != std::string::npos || next.empty() ||
        next[0] == '-')
      continue;
    const CLI::Option* o = verb->get_option_no_throw(arg);
    if (!o || o->get_expected_max() != 0) continue;
    // The parser named its extras: the word after the flag must be one (in
    // `post --clamp IN -o OUT EXTRA`, IN is the input, EXTRA the stray), or
    // a file for --json (`post --json P.json IN`: P.json took IN's place).
    const bool json_file =
        arg == "--json" && next.size() > 5 && next.compare(next.size() - 5, 5, ".json") == 0;
    if (!extras.empty() && extras.find(next) == std::string::npos && !json_file) continue;
    std::string why = arg + " of volmap " + verb->get_name() + " takes no value, so '" + next +
                      "' after it was not expected";
    if (arg == "--json")
      why += ": it writes the JSON to standard output (redirect it: > " + next +
             "); only volmap explain's --json names a file";
    return why;
  }
  return {};
}

std::string plain_range(const std::string& message) {
  // PositiveNumber is Range(smallest positive double, largest double): its
  // bounds printed with std::to_string.
  static const std::regex kPositive(R"(Value (\S+) not in range 0\.000000 to [0-9]{30,}\.000000)");
  return std::regex_replace(message, kPositive, "value $1 must be positive");
}

}  // namespace volmap::cli
