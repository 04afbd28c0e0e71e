#include "core/common/atomic_file.h"

#include <fmt/format.h>
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

std::string error_message(const char* format, const std::string& path, const std::string& reason) {
  return fmt::format(fmt::runtime(format), fmt::arg("path", path), fmt::arg("reason", reason));
}

std::filesystem::path normalised(const std::string& p) {
  std::error_code ec;
  std::filesystem::path out = std::filesystem::weakly_canonical(p, ec);
  if (ec) out = std::filesystem::absolute(p, ec).lexically_normal();
  return out;
}
}  // namespace

void refuse_output_equal_to_input(const std::string& output, const std::vector<std::string>& inputs,
                                  const AtomicOutputWording& wording) {
  if (output == "-") return;
  const std::filesystem::path out = normalised(output);
  for (const std::string& in : inputs) {
    if (in.empty() || in == "-") continue;
    std::error_code ec;
    const bool same_file = std::filesystem::equivalent(output, in, ec) && !ec;
    if (same_file || normalised(in) == out)
      throw std::invalid_argument(fmt::format(fmt::runtime(wording.output_is_input),
                                              fmt::arg("output", output), fmt::arg("input", in)));
  }
}

AtomicOutput::AtomicOutput(std::string path, const std::vector<std::string>& inputs,
                           const AtomicOutputWording& wording)
    : path_(std::move(path)), wording_(wording) {
  refuse_output_equal_to_input(path_, inputs, wording_);
  if (path_ == "-" && wording_.dash_is_stdout) {
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
    throw std::runtime_error(error_message(wording_.cannot_create, path_, reason));
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
    throw std::runtime_error(error_message(wording_.write_error, path_, ""));
  }
  if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    const std::string reason = std::generic_category().message(errno);
    std::remove(temp_path_.c_str());
    committed_ = true;
    throw std::runtime_error(error_message(wording_.cannot_rename, path_, reason));
  }
  committed_ = true;
}

}  // namespace volmap
