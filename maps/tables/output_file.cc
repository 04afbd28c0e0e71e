#include "maps/tables/output_file.h"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <system_error>

namespace volmap::maps {

namespace fs = std::filesystem;

void refuse_output_equal_to_input(const std::string& output,
                                  const std::vector<std::string>& inputs) {
  if (output == "-") return;
  std::error_code ec;
  const fs::path out = fs::weakly_canonical(fs::absolute(output, ec), ec);
  for (const std::string& in : inputs) {
    if (in.empty() || in == "-") continue;
    std::error_code ec2;
    const fs::path p = fs::weakly_canonical(fs::absolute(in, ec2), ec2);
    bool same = !ec && !ec2 && out == p;
    if (!same && fs::exists(output, ec2) && fs::exists(in, ec2))
      same = fs::equivalent(output, in, ec2) && !ec2;
    if (same)
      throw std::invalid_argument(
          fmt::format("{}: the output is the input file {}; write to another path", output, in));
  }
}

OutputFile::OutputFile(std::string path) : path_(std::move(path)) {
  static std::atomic<int> counter{0};
  temp_path_ = fmt::format("{}.tmp-{}-{}", path_, static_cast<long>(getpid()), ++counter);
  file_.open(temp_path_, std::ios::binary | std::ios::trunc);
  if (!file_)
    throw std::runtime_error(
        fmt::format("{}: cannot create the file ({}); check the folder exists "
                    "and is writable",
                    path_, std::strerror(errno)));
}

OutputFile::~OutputFile() {
  if (!committed_ && !temp_path_.empty()) {
    if (file_.is_open()) file_.close();
    std::remove(temp_path_.c_str());
  }
}

void OutputFile::commit() {
  file_.flush();
  const bool ok = static_cast<bool>(file_);
  file_.close();
  if (!ok || file_.fail())
    throw std::runtime_error(fmt::format("{}: write error (disk full?)", path_));
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0)
    throw std::runtime_error(fmt::format("{}: cannot rename the temporary file onto it ({})", path_,
                                         std::strerror(errno)));
  committed_ = true;
}

}  // namespace volmap::maps
