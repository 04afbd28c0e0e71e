// The deviation along a verified tool path, kept small enough to plot
// whatever the program's size: volmap verify --report.
//
// Samples arrive in path order with their distance along the path (mm of
// tool-tip travel of the program being run, rapids excluded), their tip
// deviation (um) and, for five axes, their tool-axis deviation (urad). They
// are binned by path length; bins start 1 mm wide and double (adjacent pairs
// merged) whenever more than kMaxBins would be needed, so memory is fixed
// and every bin keeps the exact maximum of its samples. The worst program
// lines (largest tip deviation per line) are kept as a top-N list: a line's
// samples are contiguous, so one pass suffices.
#pragma once

#include <cstdint>
#include <vector>

namespace volmap::post {

struct ProfileBin {
  double max_um = 0.0;    ///< largest tip deviation in the bin
  double max_urad = 0.0;  ///< largest tool-axis deviation (five axes)
  int line = 0;           ///< program line of max_um
  std::uint64_t samples = 0;
};

struct WorstLine {
  int line = 0;
  double max_um = 0.0;
};

class DeviationProfile {
 public:
  static constexpr int kMaxBins = 512;
  static constexpr int kWorstLines = 10;

  void add(double path_mm, double dev_um, double dev_urad, int line);

  /// Bin width (mm of path) and the bins, bin k covering [k w, (k+1) w).
  double bin_width_mm() const { return width_mm_; }
  const std::vector<ProfileBin>& bins() const { return bins_; }
  double path_length_mm() const { return path_mm_; }
  bool has_angles() const { return has_angles_; }
  /// The worst lines, largest first (ties: lower line first).
  std::vector<WorstLine> worst_lines() const;

 private:
  void close_line();

  double width_mm_ = 1.0;
  double path_mm_ = 0.0;
  bool has_angles_ = false;
  std::vector<ProfileBin> bins_;
  std::vector<WorstLine> worst_;  ///< at most kWorstLines, unordered
  WorstLine current_;
  bool have_current_ = false;
};

}  // namespace volmap::post
