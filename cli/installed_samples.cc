#include "cli/installed_samples.h"

#include <filesystem>
#include <set>
#include <system_error>

namespace volmap::cli {

namespace fs = std::filesystem;

std::string installed_samples_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const fs::path dir = exe.parent_path().parent_path() / "share" / "volmap" / "samples";
  if (!fs::is_directory(dir, ec)) return {};
  return fs::canonical(dir, ec).string();
}

std::vector<std::string> with_installed_samples(const std::vector<std::string>& args,
                                                const std::string& samples_dir,
                                                std::vector<std::string>* notes) {
  std::vector<std::string> out = args;
  if (samples_dir.empty()) return out;
  static const std::set<std::string> kOutputs = {"-o", "--output", "--report", "--json"};
  static const std::string kPrefix = "samples/";
  for (std::size_t i = 1; i < out.size(); ++i) {
    if (kOutputs.count(args[i - 1])) continue;
    std::string& a = out[i];
    const std::size_t eq = a.rfind("--", 0) == 0 ? a.find('=') : std::string::npos;
    if (eq != std::string::npos && kOutputs.count(a.substr(0, eq))) continue;
    const std::size_t start = eq == std::string::npos ? 0 : eq + 1;
    if (a.compare(start, kPrefix.size(), kPrefix) != 0) continue;
    const std::string path = a.substr(start);
    std::error_code ec;
    if (fs::exists(path, ec)) continue;
    const fs::path installed = fs::path(samples_dir) / path.substr(kPrefix.size());
    if (!fs::is_regular_file(installed, ec)) continue;
    a = a.substr(0, start) + installed.string();
    if (notes)
      notes->push_back(path + " is not in this folder: using the installed sample " +
                       installed.string());
  }
  return out;
}

}  // namespace volmap::cli
