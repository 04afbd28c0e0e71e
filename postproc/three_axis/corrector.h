// The correction of a commanded point of a three-axis machine: the position
// to command so that the actual tool tip lands on the nominal one, the
// solution of  x_cmd + e(x_cmd) = x_nominal  (Hsu Fig. 5, "-du", solved
// exactly by fixed-point iteration rather than to first order).
//
// Frames: machine coordinates of the controlled point (mm), as LinuxCNC uses
// them: program position + work offset. The machine file's tool
// (tool.length_mm) is the reference tool: for it, machine coordinates are the
// machine's axis values. A tool of another length L (G43) puts its tip where
// the reference tool's would be, by shifting the axes (tool length
// compensation); its error is that of the machine with tool length L at the
// shifted axes (angular errors times the longer lever).
#pragma once

#include <Eigen/Core>
#include <array>
#include <limits>
#include <memory>

#include "core/model/error_model.h"

namespace volmap::maps {
struct VolumetricTable;
}

namespace volmap::post {

class Corrector {
 public:
  /// `machine` must have exactly three linear axes and no rotary axis.
  Corrector(const Machine& machine, const ErrorSet& errors, double tool_length_mm,
            OutsidePolicy outside);
  /// The same from a compensation table (volmap map) of a three-axis
  /// machine: the error at a commanded point is the table's tool-tip error
  /// (ex ey ez) interpolated as the table was checked (its checked_with), in
  /// the direction layer of the approach directions (the mean of the layers
  /// for an axis not yet moved, as the model takes the mean of its tables).
  /// A table holds the errors of the machine file's tool only: the tool
  /// length is that one. No bounds of the field are derived from a table
  /// (lipschitz_bound() and curvature_bound() are infinite): straight pieces
  /// are checked by samples. `table` must outlive the Corrector. Throws
  /// std::invalid_argument for a table that is not a three-axis table of
  /// this machine.
  Corrector(const Machine& machine, const maps::VolumetricTable& table, OutsidePolicy outside);

  /// Tool-tip error at commanded machine position p (mm, machine frame),
  /// as a displacement in machine coordinates: actual = p + error_at(p).
  Eigen::Vector3d error_at(const Eigen::Vector3d& p_machine_mm,
                           const ApproachDirections& dir) const;
  /// Lost motion as play (a backlash operator): the error with each axis's
  /// hysteresis state h in [-1, 1] (-1: taken up moving -, +1: moving +),
  /// blending the two directions' tables: e = e(mean) + sum_a h_a (e(a+) - e(a-)) / 2
  /// (first order in the direction difference).
  Eigen::Vector3d error_with_play(const Eigen::Vector3d& p_machine_mm,
                                  const Eigen::Vector3d& h) const;
  /// Width of the play of axis a at p: |EKK(+) - EKK(-)| of its positioning
  /// error (mm); 0 for an axis without bidirectional data.
  double play_width_mm(int a, const Eigen::Vector3d& p_machine_mm) const;
  bool bidirectional(int a) const { return bidirectional_[static_cast<size_t>(a)]; }
  /// The jump of the error at p when axis a turns round: the two
  /// directions' errors apart (the other axes as d says; 0 without play).
  double reversal_jump_mm(const Eigen::Vector3d& p_machine_mm, int a, ApproachDirections d) const;
  /// The backlash operator (verify's, the kept arcs'): the commanded point
  /// moves from `from` to `to`; each axis with play moves its state h
  /// (error_with_play) across the play by twice its travel over the play's
  /// width, clamped to [-1, 1] (an axis of no width: at once).
  void take_up_play(const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                    Eigen::Vector3d& h) const;
  /// Whether the error is the same function under both direction sets (they
  /// differ only for axes without bidirectional data).
  bool same_error(const ApproachDirections& a, const ApproachDirections& b) const {
    for (std::size_t k = 0; k < 3; ++k)
      if (bidirectional_[k] && a[k] != b[k]) return false;
    return true;
  }

  /// The commanded position whose actual tip is p_nominal: the fixed point
  /// of x = p - e(x) to 1e-12 mm.
  Eigen::Vector3d command_for(const Eigen::Vector3d& p_nominal_mm,
                              const ApproachDirections& dir) const;
  /// The same, warm-started from the correction (command - nominal) of a
  /// nearby point, to within accuracy_mm of the fixed point (certified by
  /// the Lipschitz bound): with a good start and 1e-9 mm, one or two
  /// evaluations of e instead of four.
  Eigen::Vector3d command_for(const Eigen::Vector3d& p_nominal_mm, const ApproachDirections& dir,
                              const Eigen::Vector3d& nearby_correction_mm,
                              double accuracy_mm = 1e-12) const;

  /// Bounds of the error field inside the box where every axis's tables
  /// hold (machine frame, any approach directions, docs/post.md "Bounds"):
  ///   |De(x) v| <= lipschitz_bound() |v|,  |D2e(x)[v, v]| <= curvature_bound() |v|^2.
  /// From the tables' per-interval maxima of |value|, |slope| and |second
  /// derivative| and the three-axis chain's levers (affine in the axes):
  /// first order, times a safety factor of 1.5 for the terms of second
  /// order in the errors (relative 1e-4 on a real machine).
  double lipschitz_bound() const { return lipschitz_; }
  double curvature_bound() const { return curvature_; }
  /// Whether p (machine frame) lies inside that box.
  bool in_bound_box(const Eigen::Vector3d& p_machine_mm) const;
  /// Bound of the deviation from the chord, max over t of
  /// |e(c0 + t (c1 - c0)) - ((1 - t) e(c0) + t e(c1))| <= K |c1 - c0|^2 / 8,
  /// or +infinity when c0 or c1 lies outside the box.
  double chord_deviation_bound(const Eigen::Vector3d& c0, const Eigen::Vector3d& c1) const;
  /// The machine's axis positions where the controlled point p (machine
  /// frame) stands with this tool (tool length compensation moves the axes).
  Eigen::Vector3d axis_position(const Eigen::Vector3d& p_machine_mm) const {
    return p_machine_mm + axis_shift_mm_;
  }
  /// True when the machine has no errors at all (the output must equal the input).
  bool zero() const { return zero_; }

 private:
  std::unique_ptr<ErrorModel> model_;  ///< null for a table
  const maps::VolumetricTable* table_ = nullptr;
  OutsidePolicy outside_ = OutsidePolicy::kError;
  Eigen::Vector3d table_error(const Eigen::Vector3d& u_mm, const ApproachDirections& dir) const;
  Eigen::Matrix3d M_u_tip_;        ///< d(machine coordinate)/d(tip, workpiece frame)
  Eigen::Vector3d axis_shift_mm_;  ///< tool length compensation of this tool
  bool zero_ = false;
  std::array<bool, 3> bidirectional_{};
  double lipschitz_ = 0.0, curvature_ = 0.0;
  /// iterate()'s certificate, L / (1 - L) (infinite for L >= 0.5), computed once.
  double step_factor_ = std::numeric_limits<double>::infinity();
  /// M_u_tip_ is the identity (a machine whose axes move the tip along
  /// +x, +y, +z): error_at skips the product.
  bool identity_u_tip_ = false;
  void finish_setup();
  Eigen::Vector3d box_lo_ = Eigen::Vector3d::Zero(),
                  box_hi_ = Eigen::Vector3d::Zero();  ///< machine frame
  void compute_bounds(const Machine& machine, const ErrorSet& errors);
  Eigen::Vector3d iterate(const Eigen::Vector3d& p_nominal, const ApproachDirections& dir,
                          Eigen::Vector3d x, double accuracy_mm) const;
};

}  // namespace volmap::post
