#include "postproc/three_axis/self_check.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/common/input_error.h"
#include "gcode/flatten/flattener.h"
#include "gcode/g_codes.h"
#include "gcode/nc_path.h"

namespace volmap::post {

using Eigen::Vector3d;

namespace {
// A cycle's hole as a feed move: from its R plane down to its bottom.
nc::Motion feed_in(const nc::Motion& h) {
  nc::Motion m = h;
  m.kind = nc::MotionKind::kLinear;
  m.start_mm = Vector3d(h.end_mm.x(), h.end_mm.y(), h.r_mm);
  return m;
}
}  // namespace

SelfCheck::SelfCheck(const nc::Interpreter& post, const nc::ProgramSetup& setup,
                     const std::string& file, double tolerance_mm)
    : post_(post), interp_(setup, file), tolerance_mm_(tolerance_mm), file_(file) {}

void SelfCheck::set_anchor_radius(const Corrector& c) {
  // The expansion's remainder at the radius a quarter of the tolerance:
  // kappa (r^2/2 + sqrt(3)/2 h r) = tol / 4 (at most 20 mm).
  const double kappa = c.curvature_bound(), b = 0.8660254037844387 * kAnchorStepMm;
  anchor_radius_mm_ =
      kappa > 0 ? std::min(20.0, -b + std::sqrt(b * b + tolerance_mm_ / (2 * kappa))) : 20.0;
}

void SelfCheck::push(const nc::Motion& m) { current_.push_back({m, true}); }

void SelfCheck::nominal(const nc::Motion& m, const std::vector<nc::Motion>* more_holes) {
  first_line_ = lines_with_motion_++ == 0;
  // The last line's moves join the ring of those before it.
  for (const Nominal& n : current_) {
    head_ = (head_ + 1) % ring_.size();
    ring_[head_] = n;
  }
  current_.clear();
  switch (m.kind) {
    case nc::MotionKind::kLinear:
    case nc::MotionKind::kArc:
      push(m);
      return;
    case nc::MotionKind::kCycle:
      push(feed_in(m));
      if (more_holes)
        for (const nc::Motion& h : *more_holes) push(feed_in(h));
      return;
    case nc::MotionKind::kTap:
      push(m);
      return;
    case nc::MotionKind::kRapid:
      return;
  }
}

void SelfCheck::skipped(std::string_view text) {
  out_line_ += static_cast<long>(std::count(text.begin(), text.end(), '\n'));
}

void SelfCheck::written(std::string_view text, const Corrector& c, const std::string& file,
                        int line) {
  if (!dialect_set_) {
    interp_.set_dialect(post_.setup().dialect);
    dialect_set_ = true;
    set_anchor_radius(c);
  }
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    const std::string_view t = text.substr(0, nl);
    ++out_line_;
    read_line(nc::flatten::without_cr(t), c, file, line);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
  }
}

void SelfCheck::read_line(std::string_view t, const Corrector& c, const std::string& file,
                          int line) {
  const nc::Motion* m = nullptr;
  const std::vector<nc::Motion>* holes = nullptr;
  bool m_plain = false;
  try {
    // As the reader reads a program: a line of axis words through the
    // interpreter's shortcut, any other as a block.
    if (nc::lex_plain_axis_words(t, plain_) &&
        interp_.execute_linear_axes(plain_.value, plain_.given, plain_motion_, plain_.g1 != 0)) {
      m = &plain_motion_;
      m_plain = true;
      named_ |= plain_.given;
    } else {
      nc::lex_block_into(t, static_cast<int>(out_line_), file_, block_);
      interp_.execute(block_, fx_);
      if (fx_.has_motion) {
        m = &fx_.motion, holes = &fx_.more_holes;
        named_ |= fx_.homed_axes;
        for (const nc::Word& w : block_.words)
          named_ |= w.letter >= 'X' && w.letter <= 'Z'   ? 1u << (w.letter - 'X')
                    : w.letter == '@' || w.letter == '^' ? 3u
                                                         : 0u;
      }
    }
  } catch (const InputError& e) {
    throw InputError(file, line,
                     fmt::format("self-check: line {} of the written program does not read back "
                                 "({}), so nothing was written. This is a volmap bug: please "
                                 "report it with the program, machine and errors files",
                                 out_line_, e.what()));
  }
  if (!m) return;
  if (!moved_) previous_ = m->start_mm;  // where the machine stands at the start
  // A block-delete line may run or not (the operator's switch): the post
  // writes it as it is and goes on from its nominal end; run, not measured.
  from_skipped_ = skip_;  // (a move after one: its start is not corrected; its end is measured)
  skip_ = !m_plain && block_.block_delete;
  if (m->kind == nc::MotionKind::kLinear || m->kind == nc::MotionKind::kArc) {
    feed(*m, c, file, line);
  } else if (m->kind == nc::MotionKind::kCycle) {
    hole(*m, c, file, line);
    if (holes)
      for (const nc::Motion& h : *holes) hole(h, c, file, line);
  } else if (m->kind == nc::MotionKind::kTap) {
    // In to the bottom and back out: the bottom is the program's point.
    take_up(c, m->end_mm);
    measure(m->end_mm, c, file, line);
    take_up(c, m->start_mm);
    have_actual_ = false;
  } else {  // a rapid: not cutting, but it moves the axes (and their play)
    take_up(c, m->end_mm);
    have_actual_ = false;
  }
  moved_ = true;
}

void SelfCheck::take_up(const Corrector& c, const Vector3d& to) {
  // (An axis already at the end of its play in its direction of travel
  // stays: no table lookup for the play's width.)
  bool changes = false;
  for (int a = 0; a < 3 && !changes; ++a) {
    const double travel = to[a] - previous_[a];
    changes = travel != 0.0 && c.bidirectional(a) && play_[a] != (travel > 0 ? 1.0 : -1.0);
  }
  if (changes) c.take_up_play(previous_, to, play_);
  previous_ = to;
}

Vector3d SelfCheck::actual(const Corrector& c, const Vector3d& x) {
  // The play at an end (or unknown, 0) on every axis: the error of those
  // approach directions (error_with_play's mean of the two directions is
  // it to the model's second order); else the play's blend, exactly.
  bound_mm_ = 0.0;
  ApproachDirections d{};
  for (int a = 0; a < 3; ++a) {
    const double h = play_[a];
    if (h != 0.0 && h != 1.0 && h != -1.0) return x + c.error_with_play(x, play_);
    d[static_cast<std::size_t>(a)] = static_cast<std::int8_t>(h);
  }
  // Near an anchor of the same directions, inside the box where the
  // field's bounds hold: its first-order expansion, off the model by at
  // most kappa/2 |dx|^2 (the curvature bound) plus the forward difference's
  // error, sqrt(3) kappa h / 2 |dx| (docs/post.md "Self-check").
  const double kappa = c.curvature_bound();
  const Vector3d dx = x - anchor_x_;
  const double r = dx.norm();
  if (anchor_valid_ && !exact_ && d == anchor_dirs_ && r <= anchor_radius_mm_ &&
      c.in_bound_box(x)) {
    bound_mm_ = kappa * (0.5 * r * r + 0.8660254037844387 * kAnchorStepMm * r);
    return x + anchor_e_ + anchor_j_ * dx;
  }
  const Vector3d e = c.error_at(x, d);
  anchor_valid_ = std::isfinite(kappa) && c.in_bound_box(x);
  if (anchor_valid_) {
    // A new anchor: the error and its forward differences (three more
    // evaluations, kept for the points within kAnchorRadiusMm).
    for (int a = 0; a < 3; ++a) {
      Vector3d xh = x;
      xh[a] += kAnchorStepMm;
      anchor_valid_ = anchor_valid_ && c.in_bound_box(xh);
      anchor_j_.col(a) = (c.error_at(xh, d) - e) / kAnchorStepMm;
    }
    anchor_x_ = x;
    anchor_e_ = e;
    anchor_dirs_ = d;
  }
  return x + e;
}

bool SelfCheck::smooth_line(const nc::Motion& m, const Corrector& c) {
  // A straight move with the play already taken up in its direction on
  // every axis that moves: the actual path is the chord of its actual ends
  // within L^2/8 of the field's curvature bound (docs/post.md "Bounds"),
  // and the distance to a straight nominal move is convex along the chord:
  // the ends, measured against the same nominal move, bound every point.
  const Vector3d v = m.end_mm - previous_;
  for (int a = 0; a < 3; ++a)
    if (v[a] != 0.0 && c.bidirectional(a) && play_[a] != (v[a] > 0 ? 1.0 : -1.0)) return false;
  if (named_ != 7u || skip_ || !c.in_bound_box(previous_) || !c.in_bound_box(m.end_mm))
    return false;
  const double sag = v.squaredNorm() / 8 * c.curvature_bound();
  if (!(sag < 0.25 * tolerance_mm_)) return false;
  double start_bound = last_bound_mm_;
  Vector3d start = last_actual_;
  if (!have_actual_) {
    start = actual(c, previous_);
    start_bound = bound_mm_;
  }
  previous_ = m.end_mm;
  last_actual_ = actual(c, m.end_mm);
  last_bound_mm_ = bound_mm_;
  have_actual_ = true;
  const Nominal* near = nearest(last_actual_);
  if (!near || near->motion.kind != nc::MotionKind::kLinear) return false;
  const double d = std::max(nc::distance_to_path(near->motion, last_actual_) + last_bound_mm_,
                            nc::distance_to_path(near->motion, start) + start_bound) +
                   sag;
  if (d > tolerance_mm_) return false;  // beyond it by the bound: the points decide
  ++stats_.points;
  stats_.max_mm = std::max(stats_.max_mm, d);
  return true;
}

void SelfCheck::feed(const nc::Motion& m, const Corrector& c, const std::string& file, int line) {
  const bool arc = m.kind == nc::MotionKind::kArc;
  const Vector3d start = previous_;
  if (!first_line_ && !from_skipped_ && !arc && smooth_line(m, c)) return;
  previous_ = start;
  const double len = nc::path_length_mm(m);
  const double n_real = std::ceil(len / (arc ? kArcStepMm : kLineStepMm));
  // (A move too long to sample has been refused by the travel check.)
  int n = n_real < 1e7 ? std::max(1, static_cast<int>(n_real)) : 10'000'000;
  if (arc) n = std::max(n, kArcSamples);
  for (int k = from_skipped_ ? n : 1; k <= n; ++k) {
    const Vector3d x = k == n ? m.end_mm : nc::point_on(m, static_cast<double>(k) / n);
    take_up(c, x);
    measure(x, c, file, line);
  }
}

void SelfCheck::hole(const nc::Motion& h, const Corrector& c, const std::string& file, int line) {
  // Over the hole, down to R and feed to the bottom (measured), back out.
  take_up(c, Vector3d(h.end_mm.x(), h.end_mm.y(), h.r_mm));
  take_up(c, h.end_mm);
  measure(h.end_mm, c, file, line);
  take_up(c, Vector3d(h.end_mm.x(), h.end_mm.y(), h.clear_mm));
  have_actual_ = false;
}

const SelfCheck::Nominal* SelfCheck::nearest(const Vector3d& p) {
  // The line's own moves first (the newest: almost always the one), then
  // those of the lines before it.
  const Nominal* best = nullptr;
  best_mm_ = std::numeric_limits<double>::infinity();
  const auto look = [&](const Nominal& nm) {
    if (const double d = nc::distance_to_path(nm.motion, p); d < best_mm_) {
      best_mm_ = d;
      best = &nm;
    }
    return best_mm_ <= tolerance_mm_;
  };
  for (auto it = current_.rbegin(); it != current_.rend(); ++it)
    if (look(*it)) return best;
  for (std::size_t k = 0; k < ring_.size(); ++k) {
    const Nominal& nm = ring_[(head_ + ring_.size() - k) % ring_.size()];
    if (!nm.valid || look(nm)) break;
  }
  return best;
}

void SelfCheck::measure(const Vector3d& x, const Corrector& c, const std::string& file, int line) {
  // The program's first move starts where the machine stood before it (the
  // post's creep to its corrected start, the play taken up on the way in);
  // until the program has named every axis, the others stand there too:
  // not the program's points, nor the post's.
  if (first_line_ || skip_ || named_ != 7u) {
    have_actual_ = false;
    return;
  }
  last_actual_ = actual(c, x);
  last_bound_mm_ = bound_mm_;
  have_actual_ = true;
  ++stats_.points;
  if (!nearest(last_actual_)) return;  // no nominal feed yet: a move the input did not cut
  if (best_mm_ + last_bound_mm_ > tolerance_mm_ && last_bound_mm_ > 0) {
    // Beyond it by the expansion's bound: the model itself decides.
    exact_ = true;
    last_actual_ = actual(c, x);
    exact_ = false;
    last_bound_mm_ = 0.0;
    nearest(last_actual_);
  }
  const double best = best_mm_ + last_bound_mm_;
  stats_.max_mm = std::max(stats_.max_mm, best);
  if (best <= tolerance_mm_ * (1 + 1e-9)) return;
  throw InputError(
      file, line,
      fmt::format("self-check: line {} of the written program, read back and run on the "
                  "simulated machine, leaves this line's nominal path by {:.2f} µm (the "
                  "tolerance is {:g} µm), so nothing was written. This is a volmap bug: please "
                  "report it with the program, machine and errors files (`no_self_check` "
                  "writes the program unchecked)",
                  out_line_, best * 1e3, tolerance_mm_ * 1e3));
}

}  // namespace volmap::post
