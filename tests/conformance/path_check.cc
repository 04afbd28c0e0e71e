#include "tests/conformance/path_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "gcode/nc_path.h"

namespace volmap::conformance {

ErrorField::ErrorField(const Machine& machine, ErrorSet errors)
    : machine_(machine), errors_(std::move(errors)) {}

const post::Corrector& ErrorField::corrector(double tool_offset_mm) const {
  const long long key = std::llround(tool_offset_mm * 1e6);
  auto& c = by_length_[key];
  if (!c)
    c = std::make_unique<post::Corrector>(
        machine_, errors_, machine_.tool_length_mm + tool_offset_mm, OutsidePolicy::kClamp);
  return *c;
}

namespace {

constexpr double kSampleMm = 0.5;

// rs274 prints 4 decimals of the program's unit: half a unit on each axis.
double rounding_um(double unit_mm) { return 0.5e-4 * unit_mm * 1e3 * std::sqrt(3.0); }

bool moves(const CanonMove& m) {
  return m.motion.kind == nc::MotionKind::kArc || (m.motion.end_mm - m.motion.start_mm).norm() > 0;
}

// Whether the move starts where the controller stands uncorrected (the
// axes at one of `stands_at`; the tip a tool length offset below them).
bool starts_uncorrected(const CanonMove& m, const std::vector<Eigen::Vector3d>& stands_at) {
  for (const Eigen::Vector3d& axes : stands_at) {
    const Eigen::Vector3d tip = axes - Eigen::Vector3d(0, 0, m.tool_offset_mm);
    if ((m.motion.start_mm - tip).norm() < 1e-6) return true;
  }
  return false;
}

int samples(const CanonMove& m) {
  return std::max(1, static_cast<int>(std::ceil(nc::path_length_mm(m.motion) / kSampleMm)));
}

// The nearest of a list of moves to p, searched around the cursor first and
// over the whole list when that finds nothing within 0.5 um (a path that comes
// back over itself). dist(i, p): the distance to move i.
template <typename Dist>
double nearest(size_t count, size_t& cursor, Dist dist) {
  double best = 1e300;
  size_t best_i = cursor;
  const size_t from = cursor > 3 ? cursor - 3 : 0, to = std::min(count, cursor + 6);
  for (size_t i = from; i < to; ++i)
    if (const double d = dist(i); d < best) best = d, best_i = i;
  if (best > 5e-4)
    for (size_t i = 0; i < count; ++i)
      if (const double d = dist(i); d < best) best = d, best_i = i;
  cursor = best_i;
  return best;
}

struct Feed {
  const CanonMove* move;
  std::vector<Eigen::Vector3d> h;  // the play state at its samples (0: its start, .., n: its end)
};

// The parameter in [0, 1] of the point of the motion nearest to p, and the
// distance (mm).
std::pair<double, double> nearest_on(const nc::Motion& m, const Eigen::Vector3d& p) {
  if (m.kind != nc::MotionKind::kArc) {
    const Eigen::Vector3d d = m.end_mm - m.start_mm;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - m.start_mm).dot(d) / len2, 0.0, 1.0) : 0.0;
    return {t, (m.start_mm + t * d - p).norm()};
  }
  const nc::ArcGeometry g = nc::arc_geometry(m);
  std::pair<double, double> best = {0.0, (p - m.start_mm).norm()};
  if (const double e = (p - m.end_mm).norm(); e < best.second) best = {1.0, e};
  const double ang = std::atan2(p[g.a1] - m.center_mm[g.a1], p[g.a0] - m.center_mm[g.a0]);
  double rel = std::fmod((g.sweep >= 0 ? 1.0 : -1.0) * (ang - g.start_angle), 2 * M_PI);
  if (rel < 0) rel += 2 * M_PI;
  for (double a = rel; a <= std::abs(g.sweep) + 1e-12; a += 2 * M_PI) {
    const double s = std::clamp(a / std::abs(g.sweep), 0.0, 1.0);
    if (const double d = (nc::point_on(m, s) - p).norm(); d < best.second) best = {s, d};
  }
  return best;
}

// The play state where the command has gone from the start of the move to
// its parameter s (the backlash operator along the move, in 32 steps).
Eigen::Vector3d play_at(const Feed& f, const post::Corrector& c, double s) {
  Eigen::Vector3d h = f.h.front(), prev = f.move->motion.start_mm;
  for (int k = 1; k <= 32; ++k) {
    const Eigen::Vector3d q = nc::point_on(f.move->motion, s * k / 32);
    c.take_up_play(prev, q, h);
    prev = q;
  }
  return h;
}

// The distance from the nominal point p to the actual path of an output
// move: the commanded point the error moves to p (p - e(p), with the play
// state where the command passes it) from the commanded move.
double to_actual(const Feed& f, const Eigen::Vector3d& p, const ErrorField& field) {
  const post::Corrector& c = field.corrector(f.move->tool_offset_mm);
  const auto [s, d] = nearest_on(f.move->motion, p - c.error_with_play(p, f.h.back()));
  if (f.h.front() == f.h.back()) return d;  // no play taken up along it
  const double s1 = nearest_on(f.move->motion, p - c.error_with_play(p, play_at(f, c, s))).first;
  return nearest_on(f.move->motion, p - c.error_with_play(p, play_at(f, c, s1))).second;
}

}  // namespace

namespace {

// The play of each axis as the output's commands move it (verify's backlash
// operator), from the mean of both directions (where rs274 starts, no axis
// has moved yet).
struct Play {
  Eigen::Vector3d h = Eigen::Vector3d::Zero(), prev = Eigen::Vector3d::Zero();
  void to(const post::Corrector& c, const Eigen::Vector3d& p) {
    c.take_up_play(prev, p, h);
    prev = p;
  }
};

const char* kind_of(const CanonMove& m) {
  return m.motion.kind == nc::MotionKind::kArc ? "an arc" : "a line";
}

}  // namespace

PathDeviation compare_paths(const std::vector<CanonMove>& nominal,
                            const std::vector<CanonMove>& output, const ErrorField& field,
                            double tolerance_um, const std::vector<Eigen::Vector3d>& stands_at) {
  PathDeviation r;
  // The feeds, those that move nothing too (a point of the path: the tool
  // stands there feeding).
  std::vector<const CanonMove*> nominal_feeds;
  for (const CanonMove& m : nominal)
    if (m.feed) nominal_feeds.push_back(&m);
  r.nominal_empty = nominal_feeds.empty();
  const auto limit = [&](double unit_a, double unit_b) {
    return 1.25 * tolerance_um + rounding_um(unit_a) + rounding_um(unit_b);
  };
  // Actual to nominal: the output's moves, sampled, the play carried along.
  std::vector<Feed> output_feeds;
  Play play;
  if (!output.empty()) play.prev = output.front().motion.start_mm;
  size_t cursor = 0;
  const auto measure = [&](const Eigen::Vector3d& p, const CanonMove& m, const char* where) {
    if (nominal_feeds.empty()) return;
    const Eigen::Vector3d actual = p + field.corrector(m.tool_offset_mm).error_with_play(p, play.h);
    const double d = nearest(nominal_feeds.size(), cursor, [&](size_t i) {
      return nc::distance_to_path(nominal_feeds[i]->motion, actual);
    });
    const double um = d * 1e3, lim = limit(m.unit_mm, nominal_feeds[cursor]->unit_mm);
    if (um - lim > r.actual_to_nominal_um - r.actual_limit_um || r.actual_limit_um == 0) {
      r.actual_to_nominal_um = um;
      r.actual_limit_um = lim;
      r.actual_at = p;
      r.actual_where = where;
    }
  };
  for (size_t k = 0; k < output.size(); ++k) {
    const CanonMove& m = output[k];
    const post::Corrector& c = field.corrector(m.tool_offset_mm);
    // A change of tool length offset moves the controlled point, not the
    // axes: no play is taken up by the jump.
    play.prev = m.motion.start_mm;
    if (!m.feed) {
      play.to(c, m.motion.end_mm);
      // A cut start: where the feed that follows starts (after a jump of
      // the controlled point, if its tool's offset changed in between),
      // unless the controller stands there uncorrected.
      if (k + 1 < output.size() && output[k + 1].feed &&
          !starts_uncorrected(output[k + 1], stands_at))
        measure(output[k + 1].motion.start_mm, output[k + 1], "a cut start");
      continue;
    }
    const int n = moves(m) ? samples(m) : 0;
    Feed f{&m, {play.h}};
    const bool skip = starts_uncorrected(m, stands_at);
    for (int s = 1; s <= std::max(n, 1); ++s) {
      const Eigen::Vector3d p = nc::point_on(m.motion, n == 0 ? 1.0 : static_cast<double>(s) / n);
      play.to(c, p);
      f.h.push_back(play.h);
      if (!skip || s == n) measure(p, m, kind_of(m));
    }
    if (n == 0) f.h.pop_back();
    output_feeds.push_back(std::move(f));
  }
  r.output_empty = output_feeds.empty();
  // Nominal to actual: each sample n of the input's feeds, from the output
  // move that puts the actual tip nearest to it.
  cursor = 0;
  for (const CanonMove* m : nominal_feeds) {
    const int n = samples(*m);
    for (int s = starts_uncorrected(*m, stands_at) ? n : 0; s <= n && !output_feeds.empty(); ++s) {
      const Eigen::Vector3d p = nc::point_on(m->motion, static_cast<double>(s) / n);
      const double d = nearest(output_feeds.size(), cursor,
                               [&](size_t i) { return to_actual(output_feeds[i], p, field); });
      const double um = d * 1e3, lim = limit(m->unit_mm, output_feeds[cursor].move->unit_mm);
      if (std::getenv("CONFORMANCE_DEBUG") && um > lim) {
        const CanonMove& o = *output_feeds[cursor].move;
        std::fprintf(stderr,
                     "nominal %.4f %.4f %.4f: %.3f um from output move %zu (%s %.4f %.4f %.4f -> "
                     "%.4f %.4f %.4f, centre %.4f %.4f)\n",
                     p.x(), p.y(), p.z(), um, cursor, kind_of(o), o.motion.start_mm.x(),
                     o.motion.start_mm.y(), o.motion.start_mm.z(), o.motion.end_mm.x(),
                     o.motion.end_mm.y(), o.motion.end_mm.z(), o.motion.center_mm.x(),
                     o.motion.center_mm.y());
      }
      if (um - lim > r.nominal_to_actual_um - r.nominal_limit_um || r.nominal_limit_um == 0) {
        r.nominal_to_actual_um = um;
        r.nominal_limit_um = lim;
        r.nominal_at = p;
        r.nominal_where = kind_of(*m);
      }
    }
  }
  if (r.actual_limit_um == 0) r.actual_limit_um = limit(1, 1);
  if (r.nominal_limit_um == 0) r.nominal_limit_um = limit(1, 1);
  return r;
}

}  // namespace volmap::conformance
