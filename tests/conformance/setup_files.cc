#include "tests/conformance/setup_files.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <stdexcept>

#include "tests/conformance/process.h"

namespace volmap::conformance {

namespace fs = std::filesystem;

std::string FieldSpec::name() const {
  switch (kind) {
    case kZero:
      return "zero";
    case kSmooth:
      return fmt::format("smooth:{}", seed);
    case kLostMotion:
      return fmt::format("lost:{}", seed);
  }
  return "zero";
}

FieldSpec FieldSpec::parse(const std::string& name) {
  FieldSpec s;
  if (name == "zero") return s;
  const size_t colon = name.find(':');
  const std::string kind = name.substr(0, colon);
  if (colon == std::string::npos || (kind != "smooth" && kind != "lost"))
    throw std::invalid_argument("error field '" + name + "': zero, smooth:SEED or lost:SEED");
  s.kind = kind == "smooth" ? kSmooth : kLostMotion;
  s.seed = std::stoull(name.substr(colon + 1));
  return s;
}

namespace {

constexpr std::array<double, 3> kTravel = {500, 400, 300};
constexpr std::array<char, 3> kAxis = {'X', 'Y', 'Z'};

// A smooth function of the position t in [0, T]: a polynomial of degree 3
// and a sinusoid of 0.3 to 1.5 periods over the travel (200 mm or more),
// about `amplitude` in size.
struct Smooth {
  double c0, c1, c2, c3, a, k, phase;
  Smooth(std::mt19937_64& rng, double amplitude) {
    std::uniform_real_distribution<double> u(-1, 1);
    c0 = 0.3 * amplitude * u(rng);
    c1 = amplitude * u(rng);
    c2 = 0.6 * amplitude * u(rng);
    c3 = 0.4 * amplitude * u(rng);
    a = 0.3 * amplitude * u(rng);
    k = std::uniform_real_distribution<double>(0.3, 1.5)(rng);
    phase = std::uniform_real_distribution<double>(0, 2 * M_PI)(rng);
  }
  double operator()(double t, double T) const {
    const double s = t / T;
    return c0 + c1 * s + c2 * s * s + c3 * s * s * s + a * std::sin(2 * M_PI * k * s + phase);
  }
};

std::string zero_csv(std::uint64_t seed) {
  std::string s =
      "# volmap component errors v1\n# machine: hsu-3axis\n# source: zero (conformance)\n";
  if (seed % 2 == 0) return s;  // a file of comments only
  // The same zeros in the shape of a measured file: bidirectional rows and
  // location errors.
  s += "\nX,dir,EXX,EYX\n0,+1,0,0\n500,+1,0,0\n0,-1,0,0\n500,-1,0,0\n";
  s += "\nZ,EZZ,EAZ\n0,0,0\n300,0.0,0\n\nEC0X,EB0Z,EA0Z\n0,0,0\n";
  return s;
}

}  // namespace

std::string error_csv(const FieldSpec& spec) {
  if (spec.kind == FieldSpec::kZero) return zero_csv(spec.seed);
  std::mt19937_64 rng(spec.seed * 2654435761ULL + 17);
  std::uniform_real_distribution<double> u(0, 1);
  std::string s = fmt::format(
      "# volmap component errors v1\n# machine: hsu-3axis\n# source: conformance field {}\n",
      spec.name());
  for (int a = 0; a < 3; ++a) {
    const char A = kAxis[static_cast<size_t>(a)];
    const double T = kTravel[static_cast<size_t>(a)];
    const int rows = static_cast<int>(T / 25) + 1;
    // Positioning a few to tens of um, straightness a few um, angles a few
    // to tens of urad.
    const Smooth position(rng, 5 + 25 * u(rng));
    std::array<Smooth, 5> others = {Smooth(rng, 1 + 6 * u(rng)), Smooth(rng, 1 + 6 * u(rng)),
                                    Smooth(rng, 2 + 20 * u(rng)), Smooth(rng, 2 + 20 * u(rng)),
                                    Smooth(rng, 2 + 20 * u(rng))};
    const bool play = spec.kind == FieldSpec::kLostMotion && (a == 0 || u(rng) < 0.5);
    const double r0 = 1 + 5 * u(rng), r1 = 3 * (u(rng) - 0.5);
    // The positioning error in a block of its own (bidirectional with play).
    s += fmt::format("\n{0}{1},E{0}{0}\n", A, play ? ",dir" : "");
    for (int dir : play ? std::array<int, 2>{1, -1} : std::array<int, 2>{1, 0}) {
      if (dir == 0) break;
      for (int k = 0; k < rows; ++k) {
        const double t = std::min(T, 25.0 * k);
        const double v = position(t, T) + (dir < 0 ? r0 + r1 * t / T : 0.0);
        s += play ? fmt::format("{},{:+d},{:.4f}\n", t, dir, v) : fmt::format("{},{:.4f}\n", t, v);
      }
    }
    // The other five components of the axis.
    std::string names;
    for (char e : {'X', 'Y', 'Z', 'A', 'B', 'C'})
      if (e != A) names += fmt::format(",E{}{}", e, A);
    s += fmt::format("\n{}{}\n", A, names);
    for (int k = 0; k < rows; ++k) {
      const double t = std::min(T, 25.0 * k);
      s += fmt::format("{}", t);
      for (const Smooth& f : others) s += fmt::format(",{:.4f}", f(t, T));
      s += "\n";
    }
  }
  s += fmt::format("\nEC0X,EB0Z,EA0Z\n{:.3f},{:.3f},{:.3f}\n", 40 * (u(rng) - 0.5),
                   40 * (u(rng) - 0.5), 40 * (u(rng) - 0.5));
  return s;
}

SetupFiles write_setup_files(const std::string& dir) {
  // Machine positions (mm): G54 at the work offset, G55 and G56 near it,
  // the G28 and G30 homes above the table.
  std::map<int, double> mm;
  const auto put = [&](int first, const Eigen::Vector3d& v) {
    for (int a = 0; a < 6; ++a) mm[first + a] = a < 3 ? v[a] : 0.0;
  };
  put(5161, kG28HomeMm);
  put(5181, kG30HomeMm);
  put(5211, Eigen::Vector3d::Zero());
  put(5221, kWorkOffsetMm);
  put(5241, kWorkOffsetMm + kG55FromG54Mm);
  put(5261, kWorkOffsetMm + kG56FromG54Mm);
  SetupFiles f;
  f.volmap_var = (fs::path(dir) / "v.var").string();
  f.rs274_var = (fs::path(dir) / "i.var").string();
  std::string v, r;
  // In order (rs274 refuses a parameter file out of order): the G92 flag
  // (off) and the coordinate system in use (G54) among the positions.
  mm[5210] = 0;
  mm[5220] = 1;
  for (const auto& [n, x] : mm) {
    const bool flag = n == 5210 || n == 5220;
    v += fmt::format("{} {:.6f}\n", n, x);
    r += flag ? fmt::format("{} {}\n", n, x) : fmt::format("{} {:.10f}\n", n, x / 25.4);
  }
  write_file(f.volmap_var, v);
  write_file(f.rs274_var, r);
  f.volmap_tools = (fs::path(dir) / "v.tbl").string();
  f.rs274_tools = (fs::path(dir) / "i.tbl").string();
  std::string vt, rt;
  int n = 0;
  for (const ToolRow& t : kTools) {
    ++n;
    vt += fmt::format("T{0} P{0} Z{1} D{2} ;\n", n, t.z_mm, t.d_mm);
    rt += fmt::format("T{0} P{0} Z{1:.8f} D{2:.8f} ;\n", n, t.z_mm / 25.4, t.d_mm / 25.4);
  }
  write_file(f.volmap_tools, vt);
  write_file(f.rs274_tools, rt);
  return f;
}

}  // namespace volmap::conformance
