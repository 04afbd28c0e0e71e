// Output files that appear complete or not at all (shared/spec/cli.md):
// written to "<path>.tmp-<pid>-<n>" beside the destination and renamed onto
// it by commit(); the destructor removes an uncommitted temporary file.
// An output path naming the same file as an input is refused.
//
// (maps/ keeps its own small implementation so that it does not depend on
// work in progress elsewhere; it can move onto core/atomic_file.h later.)
#pragma once

#include <fstream>
#include <string>
#include <vector>

namespace volmap::maps {

/// Throws std::invalid_argument naming both when `output` is the same file
/// as one of `inputs` (same normalised path, or the same existing file).
void refuse_output_equal_to_input(const std::string& output,
                                  const std::vector<std::string>& inputs);

class OutputFile {
 public:
  /// Creates the temporary file (binary mode). Throws std::runtime_error
  /// naming the path when it cannot be created.
  explicit OutputFile(std::string path);
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  ~OutputFile();

  std::ostream& stream() { return file_; }
  /// Flushes, closes and renames onto the destination. Throws
  /// std::runtime_error on a write or rename error.
  void commit();
  const std::string& path() const { return path_; }

 private:
  std::string path_, temp_path_;
  std::ofstream file_;
  bool committed_ = false;
};

}  // namespace volmap::maps
