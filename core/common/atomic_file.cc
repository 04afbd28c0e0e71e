#include "core/common/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <system_error>

namespace volmap {
namespace {
std::atomic<unsigned> temp_counter{0};

std::filesystem::path normalised(const std::string& p) {
  std::error_code ec;
  std::filesystem::path out = std::filesystem::weakly_canonical(p, ec);
  if (ec) out = std::filesystem::absolute(p, ec).lexically_normal();
  return out;
}
}  // namespace

void refuse_output_equal_to_input(const std::string& output,
                                  const std::vector<std::string>& inputs) {
  if (output == "-") return;
  const std::filesystem::path out = normalised(output);
  for (const std::string& in : inputs) {
    if (in.empty() || in == "-") continue;
    std::error_code ec;
    const bool same_file = std::filesystem::equivalent(output, in, ec) && !ec;
    if (same_file || normalised(in) == out)
      throw std::invalid_argument(output + ": the output is also an input (" + in +
                                  "); write the output to another path");
  }
}

AtomicOutput::AtomicOutput(std::string path, const std::vector<std::string>& inputs)
    : path_(std::move(path)) {
  refuse_output_equal_to_input(path_, inputs);
  if (path_ == "-") {
    // Spooled: nothing reaches standard output before commit().
    to_stdout_ = true;
    std::error_code ec;
    std::filesystem::path dir = std::filesystem::temp_directory_path(ec);
    if (ec) dir = "/tmp";
    std::string templ = (dir / "volmap-stdout-XXXXXX").string();
    const int fd = ::mkstemp(templ.data());
    if (fd < 0) {
      const std::string reason = std::generic_category().message(errno);
      throw std::runtime_error("<stdout>: cannot create the spool file in " + dir.string() + " (" +
                               reason + "); set TMPDIR to a writable folder");
    }
    ::close(fd);
    temp_path_ = templ;
    file_.open(temp_path_, std::ios::binary | std::ios::trunc);
    if (!file_) throw std::runtime_error("<stdout>: cannot open the spool file " + temp_path_);
    return;
  }
  temp_path_ = path_ + ".tmp-" + std::to_string(::getpid()) + "-" +
               std::to_string(temp_counter.fetch_add(1));
  file_.open(temp_path_, std::ios::binary | std::ios::trunc);
  if (!file_) {
    const std::string reason = std::generic_category().message(errno);
    throw std::runtime_error(path_ + ": cannot create the output (" + reason +
                             "); check that the folder exists and is writable");
  }
}

AtomicOutput::~AtomicOutput() {
  if (committed_) return;
  file_.close();
  std::remove(temp_path_.c_str());
}

std::ostream& AtomicOutput::stream() { return file_; }

void AtomicOutput::commit() {
  if (committed_) return;
  if (to_stdout_) {
    file_.flush();
    const bool ok = static_cast<bool>(file_);
    file_.close();
    committed_ = true;
    if (!ok) {
      std::remove(temp_path_.c_str());
      throw std::runtime_error("<stdout>: write error in the spool file " + temp_path_ +
                               "; check the free space in TMPDIR");
    }
    {
      std::ifstream spool(temp_path_, std::ios::binary);
      if (spool.peek() != std::ifstream::traits_type::eof()) std::cout << spool.rdbuf();
    }
    std::remove(temp_path_.c_str());
    std::cout.flush();
    if (!std::cout) throw std::runtime_error("<stdout>: write error");
    return;
  }
  file_.flush();
  const bool ok = static_cast<bool>(file_);
  file_.close();
  if (!ok || file_.fail()) {
    std::remove(temp_path_.c_str());
    committed_ = true;
    throw std::runtime_error(path_ + ": write error; check the free space and the device");
  }
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    const std::string reason = std::generic_category().message(errno);
    std::remove(temp_path_.c_str());
    committed_ = true;
    throw std::runtime_error(path_ + ": cannot rename the finished output into place (" + reason +
                             ")");
  }
  committed_ = true;
}

}  // namespace volmap
