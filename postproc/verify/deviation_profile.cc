#include "postproc/verify/deviation_profile.h"

#include <algorithm>
#include <cmath>

namespace volmap::post {

void DeviationProfile::add(double path_mm, double dev_um, double dev_urad, int line) {
  if (!std::isfinite(path_mm) || path_mm < 0) path_mm = path_mm_;
  path_mm_ = std::max(path_mm_, path_mm);
  has_angles_ = has_angles_ || dev_urad > 0.0;
  auto index = [&] { return static_cast<std::size_t>(path_mm / width_mm_); };
  while (index() >= static_cast<std::size_t>(kMaxBins)) {
    // Double the width: bins 2k and 2k+1 become bin k.
    std::vector<ProfileBin> merged((bins_.size() + 1) / 2);
    for (std::size_t k = 0; k < bins_.size(); ++k) {
      ProfileBin& m = merged[k / 2];
      const ProfileBin& b = bins_[k];
      if (b.samples == 0) continue;
      if (m.samples == 0 || b.max_um > m.max_um) {
        m.max_um = b.max_um;
        m.line = b.line;
      }
      m.max_urad = std::max(m.max_urad, b.max_urad);
      m.samples += b.samples;
    }
    bins_ = std::move(merged);
    width_mm_ *= 2.0;
  }
  const std::size_t k = index();
  if (bins_.size() <= k) bins_.resize(k + 1);
  ProfileBin& b = bins_[k];
  if (b.samples == 0 || dev_um > b.max_um) {
    b.max_um = dev_um;
    b.line = line;
  }
  b.max_urad = std::max(b.max_urad, dev_urad);
  ++b.samples;

  if (!have_current_ || line != current_.line) {
    close_line();
    current_ = {line, dev_um};
    have_current_ = true;
  } else {
    current_.max_um = std::max(current_.max_um, dev_um);
  }
}

void DeviationProfile::close_line() {
  if (!have_current_) return;
  // A line seen again later (it cannot happen in path order, but be safe)
  // keeps its larger maximum.
  for (WorstLine& w : worst_)
    if (w.line == current_.line) {
      w.max_um = std::max(w.max_um, current_.max_um);
      return;
    }
  if (worst_.size() < static_cast<std::size_t>(kWorstLines)) {
    worst_.push_back(current_);
    return;
  }
  auto smallest =
      std::min_element(worst_.begin(), worst_.end(), [](const WorstLine& a, const WorstLine& b) {
        return a.max_um < b.max_um || (a.max_um == b.max_um && a.line > b.line);
      });
  if (current_.max_um > smallest->max_um) *smallest = current_;
}

std::vector<WorstLine> DeviationProfile::worst_lines() const {
  DeviationProfile copy = *this;
  copy.close_line();
  std::vector<WorstLine> out = copy.worst_;
  std::sort(out.begin(), out.end(), [](const WorstLine& a, const WorstLine& b) {
    return a.max_um > b.max_um || (a.max_um == b.max_um && a.line < b.line);
  });
  return out;
}

}  // namespace volmap::post
