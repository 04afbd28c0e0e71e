#include "tests/conformance/judge.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <regex>
#include <sstream>

#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "tests/conformance/canon.h"
#include "tests/conformance/path_check.h"
#include "tests/conformance/process.h"

namespace volmap::conformance {

namespace fs = std::filesystem;

std::string without_user_m(const std::string& text) {
  static const std::regex user_m(
      R"(^\s*(/\s*)?([Nn]\s*\d+\s*)?[Mm]\s*(1\s*\d\s*\d)((\s*[PpQq]\s*[-+]?[\d.]+)*)\s*$)");
  std::string out;
  size_t at = 0;
  while (at < text.size()) {
    size_t end = text.find('\n', at);
    end = end == std::string::npos ? text.size() : end + 1;
    std::string line = text.substr(at, end - at), ending;
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) {
      ending.insert(ending.begin(), line.back());
      line.pop_back();
    }
    // The line without its comments.
    std::string code;
    int depth = 0;
    for (char c : line) {
      if (c == ';' && depth == 0) break;
      if (c == '(') ++depth;
      if (depth == 0) code += c;
      if (c == ')' && depth > 0) --depth;
    }
    // In its place a comment rs274 prints as it runs it: `(user M102 P1 Q2)`.
    std::smatch m;
    if (std::regex_match(code, m, user_m)) {
      std::string words = "M" + m[3].str() + m[4].str();
      words.erase(std::remove_if(words.begin(), words.end(), ::isspace), words.end());
      std::string spaced;
      for (char c : words) {
        const char u = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
        if ((u == 'P' || u == 'Q') && !spaced.empty()) spaced += ' ';
        spaced += u;
      }
      line = "(user " + spaced + ")";
    }
    out += line + ending;
    at = end;
  }
  return out;
}

namespace {

const char* const kNoEnd = "File ended with no percent sign or program end";

bool unknown_user_m(const std::string& error) {
  static const std::regex r(R"(Unknown m code used: M1\d\d)");
  return std::regex_search(error, r);
}

// volmap's refusal names the file and line: "volmap: prog.ngc:12: ...".
bool names_file_line(const std::string& err) {
  static const std::regex r(R"(^volmap: [^\s:]+\.ngc:\d+)");
  return std::regex_search(err, r);
}

std::string first_line(const std::string& s) { return s.substr(0, s.find('\n')); }

// rs274's message and the line it names: "MESSAGE at `LINE`".
std::string rs274_said(const std::string& error) {
  const size_t nl = error.find('\n');
  if (nl == std::string::npos) return error;
  return error.substr(0, nl) + " at `" + first_line(error.substr(nl + 1)) + "`";
}

// A volmap message with its numbers as '#' and its file name dropped.
std::string refusal_key(const std::string& err) {
  std::string l = first_line(err);
  static const std::regex file(R"(^volmap: [^\s:]+:\d+(:\d+)?: )");
  return normalized_message(std::regex_replace(l, file, ""));
}

constexpr const char* kBom = "\xEF\xBB\xBF";

bool has_bom(const std::string& text) { return text.rfind(kBom, 0) == 0; }

// What rs274 reads in place of a program: without the byte-order mark that
// volmap reads on purpose (docs/post.md, tape frame: LinuxCNC refuses it,
// in the input as in the output), and without the user M codes rs274 alone
// cannot know.
std::string judge_copy(const std::string& text, bool strip_user_m) {
  const std::string t = has_bom(text) ? text.substr(3) : text;
  return strip_user_m ? without_user_m(t) : t;
}

void write_program(const fs::path& dir, const Program& p) {
  fs::create_directories(dir);
  write_file((dir / kProgramName).string(), p.main);
  for (const auto& [name, bytes] : p.files) write_file((dir / name).string(), bytes);
}

void write_judge_copy(const fs::path& dir, const Program& p, bool strip_user_m) {
  fs::create_directories(dir);
  write_file((dir / kProgramName).string(), judge_copy(p.main, strip_user_m));
  for (const auto& [name, bytes] : p.files)
    write_file((dir / name).string(), judge_copy(bytes, strip_user_m));
}

// Whether the output runs the same user M codes in the same order where the
// input runs them (within 0.05 mm: the corrections are micrometres): "" or
// what differs.
std::string user_m_moved(const Canon& in, const Canon& out) {
  for (size_t k = 0; k < std::max(in.user_m.size(), out.user_m.size()); ++k) {
    if (k >= in.user_m.size() || k >= out.user_m.size())
      return fmt::format("the input runs {} user M codes, the output {}", in.user_m.size(),
                         out.user_m.size());
    const UserM &a = in.user_m[k], &b = out.user_m[k];
    const Eigen::Vector3d d = b.at - a.at;
    if (a.text != b.text || d.norm() > 0.05)
      return fmt::format(
          "user M code {}: {} at X{:.4f} Y{:.4f} Z{:.4f} in, {} at X{:.4f} Y{:.4f} "
          "Z{:.4f} out (mm, machine)",
          k + 1, a.text, a.at.x(), a.at.y(), a.at.z(), b.text, b.at.x(), b.at.y(), b.at.z());
  }
  return "";
}

}  // namespace

Judge::Judge(JudgeConfig config) : config_(std::move(config)) {
  fs::create_directories(config_.work_dir);
  fs::create_directories(fs::path(config_.work_dir) / "home");
}

bool Judge::reproduces(const Program& program, const Finding& finding, double tolerance_um) {
  const Judgement j = judge(program, "shrink", {FieldSpec::parse(finding.field)}, tolerance_um);
  for (const Finding& f : j.failures)
    if (f.kind == finding.kind && f.excess_um >= finding.excess_um / 2) return true;
  return false;
}

// Where output `out` first differs from input `in` ("": nowhere).
std::string first_difference(const std::string& in, const std::string& out) {
  if (out == in) return "";
  size_t at = 0, line = 1;
  while (at < out.size() && at < in.size() && out[at] == in[at]) line += in[at++] == '\n';
  return fmt::format("first difference at line {} ({} bytes in, {} out)", line, in.size(),
                     out.size());
}

ProcessSpec Judge::post_spec(const fs::path& dir, const SetupFiles& setup, const std::string& csv,
                             const std::string& out_name, double tolerance_um, size_t k) const {
  ProcessSpec post;
  post.argv = {config_.volmap,
               "post",
               "--machine",
               (fs::path(config_.source_dir) / kMachine).string(),
               "--errors",
               csv,
               "--work-offset",
               fmt::format("{},{},{}", kWorkOffsetMm.x(), kWorkOffsetMm.y(), kWorkOffsetMm.z()),
               "--initial-position",
               fmt::format("{},{},{}", -kWorkOffsetMm.x(), -kWorkOffsetMm.y(), -kWorkOffsetMm.z()),
               "--var-file",
               setup.volmap_var,
               "--tool-table",
               setup.volmap_tools,
               "--subroutine-path",
               dir.string(),
               "--clamp",
               "--tolerance-um",
               fmt::format("{}", tolerance_um),
               kProgramName,
               "-o",
               out_name};
  post.cwd = dir.string();
  post.err_file = (dir / fmt::format("post{}.err", k)).string();
  post.timeout_s = config_.timeout_s;
  return post;
}

Judgement Judge::judge(const Program& program, const std::string& tag,
                       const std::vector<FieldSpec>& fields, double tolerance_um) {
  const fs::path dir = fs::path(config_.work_dir) / tag;
  fs::remove_all(dir);
  write_program(dir, program);
  last_dir_ = dir.string();
  const SetupFiles setup = write_setup_files(dir.string());
  Rs274Setup rs;
  rs.home = (fs::path(config_.work_dir) / "home").string();
  rs.tool_table = setup.rs274_tools;
  rs.var_file = setup.rs274_var;
  rs.scratch = dir.string();
  Judgement j;
  const bool bom = has_bom(program.main);
  if (bom) write_judge_copy(dir / "t", program, false);
  Canon in = run_rs274(rs, (dir / (bom ? "t" : ".") / kProgramName).string());
  if (!in.ok && unknown_user_m(in.error)) {
    // Judged on copies without the user M codes.
    j.user_m = true;
    write_judge_copy(dir / "t", program, true);
    in = run_rs274(rs, (dir / "t" / kProgramName).string());
  }
  const bool by_design = !in.ok && in.error.find(kNoEnd) != std::string::npos;
  j.rs274_reads = in.ok || by_design;
  j.rs274_error = in.error;
  const Machine machine = load_machine_json((fs::path(config_.source_dir) / kMachine).string());
  bool posted_with_errors = false;
  std::vector<std::string> zero_refusals;
  for (size_t k = 0; k < fields.size(); ++k) {
    const FieldSpec& field = fields[k];
    const std::string csv = (dir / fmt::format("e{}.csv", k)).string();
    write_file(csv, error_csv(field));
    const std::string out_name = fmt::format("out{}.ngc", k);
    const ProcessSpec post = post_spec(dir, setup, csv, out_name, tolerance_um, k);
    const ProcessResult r = run_process(post);
    const std::string name = field.name();
    const auto fail = [&](const std::string& kind, const std::string& detail,
                          double excess_um = 0) {
      j.failures.push_back({kind, detail, name, excess_um});
    };
    if (r.timed_out) {
      fail("volmap post timed out", fmt::format("after {} s", config_.timeout_s));
      continue;
    }
    if (r.signal != 0 || (r.exit_code != 0 && r.exit_code != 1)) {
      fail(fmt::format("volmap post crashed (exit {}, signal {})", r.exit_code, r.signal),
           first_line(r.err));
      continue;
    }
    if (r.exit_code == 1) {
      if (!names_file_line(r.err)) {
        fail("volmap refuses without file:line: " + refusal_key(r.err), first_line(r.err));
        continue;
      }
      if (!j.rs274_reads) {
        ++j.both_refused;
        continue;
      }
      j.refusals.push_back(refusal_key(r.err));
      if (field.kind == FieldSpec::kZero) zero_refusals.push_back(first_line(r.err));
      continue;
    }
    if (!j.rs274_reads) {
      fail("volmap posts a program rs274 refuses: " + normalized_message(in.error),
           "rs274: " + rs274_said(in.error) + "; volmap exits 0");
      continue;
    }
    ++j.posted;
    const std::string out_path = (dir / out_name).string();
    if (field.kind == FieldSpec::kZero) {
      if (const std::string d = first_difference(program.main, read_file(out_path)); !d.empty())
        fail("zero errors: the output differs from the input", d);
      continue;
    }
    posted_with_errors = true;
    const std::string out = read_file(out_path);
    if (bom && !has_bom(out)) fail("the byte-order mark is not written back", "");
    if (bom) write_file((dir / "t" / out_name).string(), judge_copy(out, false));
    Canon after = run_rs274(rs, (dir / (bom ? "t" : ".") / out_name).string());
    if (!after.ok && j.user_m && unknown_user_m(after.error)) {
      write_file((dir / "t" / out_name).string(), judge_copy(out, true));
      after = run_rs274(rs, (dir / "t" / out_name).string());
    }
    if (!after.ok && after.error.find(kNoEnd) == std::string::npos) {
      fail("rs274 refuses volmap's output: " + normalized_message(after.error),
           "rs274: " + rs274_said(after.error));
      continue;
    }
    if (const std::string moved = user_m_moved(in, after); !moved.empty())
      fail("volmap's output runs the user M codes elsewhere", moved);
    const ErrorField ef(machine, load_errors_csv(csv));
    const PathDeviation d = compare_paths(in.moves, after.moves, ef, tolerance_um,
                                          {Eigen::Vector3d::Zero(), kG28HomeMm, kG30HomeMm});
    j.worst_um = std::max({j.worst_um, d.actual_to_nominal_um, d.nominal_to_actual_um});
    const Eigen::Vector3d a = d.actual_at - kWorkOffsetMm, b = d.nominal_at - kWorkOffsetMm;
    // A program written back unchanged under a field with errors is a class
    // of its own (what was read as tape leader, or not read at all).
    const std::string as_read =
        r.err.find("none needed a change") != std::string::npos ? " (written as read)" : "";
    if (d.actual_fails())
      fail("the actual path leaves the nominal path at " + d.actual_where + as_read,
           fmt::format("{:.2f} um (limit {:.2f}) at X{:.4f} Y{:.4f} Z{:.4f} (mm, G54)",
                       d.actual_to_nominal_um, d.actual_limit_um, a.x(), a.y(), a.z()),
           d.actual_to_nominal_um - d.actual_limit_um);
    if (d.nominal_fails())
      fail("the nominal path is not followed on " + d.nominal_where + as_read,
           fmt::format("{:.2f} um (limit {:.2f}) at X{:.4f} Y{:.4f} Z{:.4f} (mm, G54)",
                       d.nominal_to_actual_um, d.nominal_limit_um, b.x(), b.y(), b.z()),
           d.nominal_to_actual_um - d.nominal_limit_um);
  }
  if (posted_with_errors)
    for (const std::string& z : zero_refusals)
      j.failures.push_back({"zero errors: refused what the errors posted", z, "zero", 0});
  return j;
}

}  // namespace volmap::conformance
