// The binary table file, format "volmap table" version 1, or 2 for
// five-axis tables with the correction (docs/maps.md):
// magic, header (machine, provenance, grid, channels, direction layers),
// the values as little-endian IEEE-754 doubles in the table's storage
// order, and an FNV-1a 64 checksum of every byte before it. Internal units
// (mm, rad), so a write/read round trip is exact.
#pragma once

#include <cstdint>
#include <iosfwd>
#include <string>

#include "maps/tables/volumetric_table.h"

namespace volmap::maps {

inline constexpr char kTableMagic[8] = {'V', 'O', 'L', 'M', 'A', 'P', 'T', 'B'};
inline constexpr std::uint32_t kTableVersion = 1;
/// Tables with the correction of every axis of a machine with rotary axes
/// (five-axis: ex ey ez ei ej ek ux uy uz ua uc): the same layout, version 2,
/// so that a volmap that reads version 1 only refuses them instead of
/// taking "ux" for a three-axis correction. Readers take both; the version
/// must agree with the channels.
inline constexpr std::uint32_t kTableVersionPoseCorrection = 2;

/// FNV-1a 64 (Fowler/Noll/Vo): offset basis 14695981039346656037, prime
/// 1099511628211, one byte at a time. `hash` continues a running hash.
std::uint64_t fnv1a64(const void* data, std::size_t size,
                      std::uint64_t hash = 14695981039346656037ull);

/// Writes the table. Streams the values (no copy of the table in memory).
void write_table(std::ostream& out, const VolumetricTable& table);
/// Writes to path through a temporary file renamed when complete.
void save_table(const std::string& path, const VolumetricTable& table);

/// Reads a table; `file` names it in messages. Throws InputError
/// ("file: what is wrong; what to do") for a file that is not a volmap
/// table, of another version, truncated, inconsistent or failing the
/// checksum. Allocates the values once, after checking the size.
VolumetricTable read_table(std::istream& in, const std::string& file);
VolumetricTable load_table(const std::string& path);

}  // namespace volmap::maps
