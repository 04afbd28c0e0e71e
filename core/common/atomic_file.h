// Output files that appear complete or not at all (shared/spec/cli.md:
// "written to a temporary name and renamed when complete; an output path
// equal to an input path is refused; nothing is written on failure").
//
// Usage:
//   AtomicOutput out(path, {input1, input2});  // refuses path == an input
//   write_something(out.stream());
//   out.commit();                               // rename (or flush to stdout)
// Without commit() (an exception on the way), the destructor removes the
// temporary file and the destination is untouched. "-" writes standard
// output; its text is spooled to a temporary file (in TMPDIR, or /tmp) and
// copied out at commit(), so a failure writes nothing there either, and a
// program of any size streams through in constant memory.
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace volmap {

/// How AtomicOutput words its errors (fmt format strings with the named
/// arguments {path}, {reason}, {output} and {input}) and whether "-" is
/// standard output. The callers keep the wording they have always had (the
/// bad-input goldens check it): the default is the CLI's, maps/ has its own
/// (maps/tables/output_wording.h).
struct AtomicOutputWording {
  bool dash_is_stdout = true;
  const char* cannot_create =
      "{path}: cannot create the output ({reason}); check that the folder exists and is writable";
  const char* write_error = "{path}: write error; check the free space and the device";
  const char* cannot_rename = "{path}: cannot rename the finished output into place ({reason})";
  const char* output_is_input =
      "{output}: the output is also an input ({input}); write the output to another path";
};

/// Throws std::invalid_argument when `output` names the same file as one of
/// `inputs` (same path after normalisation, or the same existing file).
/// "-" (standard input or output) is never compared.
void refuse_output_equal_to_input(const std::string& output, const std::vector<std::string>& inputs,
                                  const AtomicOutputWording& wording = {});

class AtomicOutput {
 public:
  /// Opens a temporary file beside `path` ("<path>.tmp-<pid>-<n>"). Throws
  /// std::runtime_error naming the path when it cannot be created, and
  /// std::invalid_argument when `path` equals one of `inputs`.
  explicit AtomicOutput(std::string path, const std::vector<std::string>& inputs = {},
                        const AtomicOutputWording& wording = {});
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;
  ~AtomicOutput();

  std::ostream& stream();
  /// Completes the output: checks the stream, closes and renames the
  /// temporary file onto the destination (or writes the buffered text to
  /// standard output). Throws std::runtime_error on a write error.
  void commit();

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  AtomicOutputWording wording_;
  std::string temp_path_;
  std::ofstream file_;
  bool to_stdout_ = false;
  bool committed_ = false;
};

}  // namespace volmap
