#include "maps/tables/table_file.h"

#include <fmt/format.h>

#include <bit>
#include <cstring>
#include <fstream>
#include <iostream>
#include <istream>
#include <ostream>
#include <stdexcept>

#include "core/common/input_error.h"
#include "maps/tables/output_wording.h"

namespace volmap::maps {

std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t hash) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= p[i];
    hash *= 1099511628211ull;
  }
  return hash;
}

namespace {

constexpr std::uint32_t kMaxString = 4096;
constexpr std::uint32_t kMaxChannels = 16;

// Little-endian writer with a running checksum.
class Writer {
 public:
  explicit Writer(std::ostream& out) : out_(out) {}
  void bytes(const void* p, std::size_t n) {
    hash_ = fnv1a64(p, n, hash_);
    out_.write(static_cast<const char*>(p), static_cast<std::streamsize>(n));
  }
  template <class U>
  void uint(U v) {
    unsigned char b[sizeof(U)];
    for (std::size_t i = 0; i < sizeof(U); ++i) b[i] = static_cast<unsigned char>(v >> (8 * i));
    bytes(b, sizeof(U));
  }
  void f64(double v) { uint(std::bit_cast<std::uint64_t>(v)); }
  void str(const std::string& s) {
    uint(static_cast<std::uint32_t>(s.size()));
    bytes(s.data(), s.size());
  }
  std::uint64_t hash() const { return hash_; }

 private:
  std::ostream& out_;
  std::uint64_t hash_ = 14695981039346656037ull;
};

class Reader {
 public:
  Reader(std::istream& in, const std::string& file) : in_(in), file_(file) {}
  [[noreturn]] void fail(const std::string& what) const { throw InputError(file_, 0, what); }
  void bytes(void* p, std::size_t n, const char* what) {
    in_.read(static_cast<char*>(p), static_cast<std::streamsize>(n));
    if (static_cast<std::size_t>(in_.gcount()) != n)
      fail(
          fmt::format("truncated at {} (byte {}); the file is incomplete, build it again with "
                      "volmap map",
                      what, offset_ + static_cast<std::uint64_t>(in_.gcount())));
    hash_ = fnv1a64(p, n, hash_);
    offset_ += n;
  }
  template <class U>
  U uint(const char* what) {
    unsigned char b[sizeof(U)];
    bytes(b, sizeof(U), what);
    U v = 0;
    for (std::size_t i = 0; i < sizeof(U); ++i)
      v |= static_cast<U>(static_cast<U>(b[i]) << (8 * i));
    return v;
  }
  double f64(const char* what) { return std::bit_cast<double>(uint<std::uint64_t>(what)); }
  std::string str(const char* what) {
    const std::uint32_t n = uint<std::uint32_t>(what);
    if (n > kMaxString)
      fail(fmt::format("{}: length {} is implausible; the file is damaged", what, n));
    std::string s(n, '\0');
    bytes(s.data(), n, what);
    return s;
  }
  std::uint64_t hash() const { return hash_; }
  std::uint64_t offset() const { return offset_; }

 private:
  std::istream& in_;
  const std::string& file_;
  std::uint64_t hash_ = 14695981039346656037ull;
  std::uint64_t offset_ = 0;
};

}  // namespace

void write_table(std::ostream& out, const VolumetricTable& t) {
  Writer w(out);
  w.bytes(kTableMagic, sizeof kTableMagic);
  w.uint(t.pose_correction() ? kTableVersionPoseCorrection : kTableVersion);
  w.uint(static_cast<std::uint32_t>(t.axis_count()));
  w.uint(static_cast<std::uint32_t>(t.channel_count()));
  w.uint(static_cast<std::uint32_t>(t.bidirectional_axes.size()));
  w.uint(static_cast<std::uint32_t>(t.formulation == Formulation::kDependent ? 0 : 1));
  w.uint(static_cast<std::uint32_t>(t.checked_with == Interpolation::kCubic ? 1 : 0));
  w.f64(t.tolerance_um);
  w.f64(t.achieved_um);
  w.str(t.machine_name);
  w.str(t.errors_source);
  for (const GridAxis& g : t.grid) {
    w.uint(static_cast<std::uint8_t>(axis_char(g.axis)));
    w.uint(static_cast<std::uint8_t>(g.periodic ? 1 : 0));
    w.uint(std::uint16_t{0});
    w.uint(std::uint32_t{0});
    w.f64(g.start);
    w.f64(g.spacing);
    w.f64(g.end);
    w.uint(static_cast<std::uint64_t>(g.count));
  }
  for (const std::string& c : t.channels) w.str(c);
  for (int a : t.bidirectional_axes) w.uint(static_cast<std::uint32_t>(a));
  w.uint(static_cast<std::uint64_t>(t.values.size()));
  if constexpr (std::endian::native == std::endian::little) {
    // Chunks of 1 MiB: the stream copies, the table is not duplicated.
    constexpr std::size_t kChunk = 1 << 17;
    for (std::size_t i = 0; i < t.values.size(); i += kChunk)
      w.bytes(t.values.data() + i, std::min(kChunk, t.values.size() - i) * sizeof(double));
  } else {
    for (double v : t.values) w.f64(v);
  }
  const std::uint64_t checksum = w.hash();
  w.uint(checksum);
  if (!out) throw std::runtime_error("write error while writing the table");
}

void save_table(const std::string& path, const VolumetricTable& table) {
  AtomicOutput file(path, {}, kOutputWording);
  write_table(file.stream(), table);
  file.commit();
}

namespace {

// Axis i of the grid: its letter, flags, start, spacing, end and node
// count, checked against each other.
GridAxis read_grid_axis(Reader& r, std::uint32_t i) {
  GridAxis g;
  const char letter = static_cast<char>(r.uint<std::uint8_t>("an axis letter"));
  const std::optional<AxisName> a = axis_from_char(letter);
  if (!a)
    r.fail(fmt::format("axis {}: letter '{}' is not X Y Z A B C; the file is damaged", i, letter));
  g.axis = *a;
  g.periodic = r.uint<std::uint8_t>("an axis flag") != 0;
  r.uint<std::uint16_t>("a reserved field");
  r.uint<std::uint32_t>("a reserved field");
  g.start = r.f64("an axis start");
  g.spacing = r.f64("an axis spacing");
  g.end = r.f64("an axis end");
  g.count = static_cast<std::int64_t>(r.uint<std::uint64_t>("an axis node count"));
  std::int64_t expected = -1;
  try {
    expected = node_count(g.start, g.spacing, g.end);
  } catch (const std::invalid_argument& e) {
    r.fail(fmt::format("axis {}: {}; the file is damaged", letter, e.what()));
  }
  if (expected != g.count)
    r.fail(fmt::format(
        "axis {}: {} nodes, but start {} spacing {} end {} give {}; the file is damaged", letter,
        g.count, g.start, g.spacing, g.end, expected));
  return g;
}

// Checks the remaining size before allocating (seekable streams): the values
// and the checksum, nothing more.
void check_remaining_size(Reader& r, std::istream& in, std::uint64_t expected) {
  const std::streampos here = in.tellg();
  if (here != std::streampos(-1)) {
    in.seekg(0, std::ios::end);
    const std::streampos end = in.tellg();
    in.seekg(here);
    const std::uint64_t remaining = static_cast<std::uint64_t>(end - here);
    if (remaining != expected * 8 + 8)
      r.fail(
          fmt::format("{} bytes follow the header, expected {}; the file is {}; build it again "
                      "with volmap map",
                      remaining, expected * 8 + 8,
                      remaining < expected * 8 + 8 ? "truncated" : "followed by extra bytes"));
  }
}

}  // namespace

VolumetricTable read_table(std::istream& in, const std::string& file) {
  Reader r(in, file);
  char magic[8];
  r.bytes(magic, sizeof magic, "the magic number");
  if (magic[0] == '{')
    r.fail(
        "a factorized table (JSON, `map.form` factorized) has no grid; exports take "
        "the full grid: build it with `map.form` full");
  if (std::memcmp(magic, kTableMagic, sizeof magic) != 0)
    r.fail("not a volmap table (no VOLMAPTB magic); give a file written by volmap map");
  const std::uint32_t version = r.uint<std::uint32_t>("the version");
  if (version != kTableVersion && version != kTableVersionPoseCorrection)
    r.fail(
        fmt::format("table format version {} is not supported (this volmap reads versions {} "
                    "and {}); build the table again with this volmap",
                    version, kTableVersion, kTableVersionPoseCorrection));
  VolumetricTable t;
  const std::uint32_t axes = r.uint<std::uint32_t>("the axis count");
  const std::uint32_t channels = r.uint<std::uint32_t>("the channel count");
  const std::uint32_t bidir = r.uint<std::uint32_t>("the bidirectional axis count");
  const std::uint32_t formulation = r.uint<std::uint32_t>("the formulation");
  const std::uint32_t checked = r.uint<std::uint32_t>("the interpolation");
  if (axes < 1 || axes > 6)
    r.fail(fmt::format("axis count {} is not 1..6; the file is damaged", axes));
  if (channels < 3 || channels > kMaxChannels)
    r.fail(
        fmt::format("channel count {} is not 3..{}; the file is damaged", channels, kMaxChannels));
  if (bidir > axes)
    r.fail(fmt::format("{} bidirectional axes for {} axes; the file is damaged", bidir, axes));
  if (formulation > 1 || checked > 1)
    r.fail("unknown formulation or interpolation code; the file is damaged");
  t.formulation = formulation == 0 ? Formulation::kDependent : Formulation::kIndependent;
  t.checked_with = checked == 1 ? Interpolation::kCubic : Interpolation::kLinear;
  t.tolerance_um = r.f64("the tolerance");
  t.achieved_um = r.f64("the achieved error");
  t.machine_name = r.str("the machine name");
  t.errors_source = r.str("the errors file name");
  for (std::uint32_t i = 0; i < axes; ++i) t.grid.push_back(read_grid_axis(r, i));
  for (std::uint32_t c = 0; c < channels; ++c) t.channels.push_back(r.str("a channel name"));
  if (t.channels[0] != "ex" || t.channels[1] != "ey" || t.channels[2] != "ez")
    r.fail("the first channels are not ex, ey, ez; the file is damaged");
  if ((version == kTableVersionPoseCorrection) != t.pose_correction())
    r.fail(
        fmt::format("format version {} {} the per-axis correction channels of a machine with "
                    "rotary axes; the file is damaged",
                    version, version == kTableVersionPoseCorrection ? "without" : "with"));
  for (std::uint32_t j = 0; j < bidir; ++j) {
    const std::uint32_t a = r.uint<std::uint32_t>("a bidirectional axis");
    if (a >= axes || (j > 0 && static_cast<int>(a) <= t.bidirectional_axes.back()))
      r.fail("bidirectional axes not ascending axis indices; the file is damaged");
    t.bidirectional_axes.push_back(static_cast<int>(a));
  }
  const std::uint64_t count = r.uint<std::uint64_t>("the value count");
  std::int64_t nodes = 0;
  try {
    nodes = total_nodes(t.grid);
  } catch (const std::invalid_argument& e) {
    r.fail(fmt::format("{}; the file is damaged", e.what()));
  }
  const std::uint64_t expected =
      static_cast<std::uint64_t>(nodes) * static_cast<std::uint64_t>(t.layer_count()) * channels;
  if (count != expected)
    r.fail(fmt::format("{} values, but the grid needs {}; the file is damaged", count, expected));
  check_remaining_size(r, in, expected);
  t.values.resize(static_cast<size_t>(count));
  if constexpr (std::endian::native == std::endian::little) {
    r.bytes(t.values.data(), t.values.size() * sizeof(double), "the values");
  } else {
    for (double& v : t.values) v = r.f64("the values");
  }
  const std::uint64_t computed = r.hash();
  const std::uint64_t stored = r.uint<std::uint64_t>("the checksum");
  if (stored != computed)
    r.fail(
        fmt::format("checksum mismatch (stored {:016x}, computed {:016x}): the file is damaged; "
                    "build it again with volmap map",
                    stored, computed));
  char extra;
  if (in.read(&extra, 1); in.gcount() != 0)
    r.fail("extra bytes after the checksum; the file is damaged");
  return t;
}

VolumetricTable load_table(const std::string& path) {
  if (path == "-") return read_table(std::cin, "<stdin>");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, "cannot open the table; check the path");
  return read_table(in, path);
}

}  // namespace volmap::maps
