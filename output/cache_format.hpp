#pragma once
/// The simulation cache's two kinds of file, as bytes: a frame (positions and velocities as
/// float32 in particle order, and that frame's contacts) and a checkpoint (SimulationCheckpoint,
/// exact, to continue the run bit for bit). Files, their names and when they are written are the
/// cache writer's; this only turns records into bytes and back, checking every byte on the way
/// back.
///
/// Every file is a 64-byte header followed by its payload, all little-endian:
///
/// | offset | type      | field                                                        |
/// |-------:|-----------|--------------------------------------------------------------|
/// | 0      | char[8]   | magic `SBCACHE` and a zero byte                              |
/// | 8      | uint32    | format version, 1                                            |
/// | 12     | uint32    | kind: 1 frame, 2 checkpoint                                  |
/// | 16     | int32     | frame number (1 is the initial state)                        |
/// | 20     | uint32    | particles                                                    |
/// | 24     | uint32    | frame: contacts; checkpoint: touching triangle pairs         |
/// | 28     | uint32    | bytes per scalar: 4 (8 in a double-precision build's checkpoint) |
/// | 32     | float64   | time, seconds                                                |
/// | 40     | uint64    | payload bytes                                                |
/// | 48     | uint32    | CRC-32 (zlib's) of the payload                               |
/// | 52     | uint32    | CRC-32 of header bytes 0–51                                  |
/// | 56     | uint64    | zero                                                         |
///
/// A frame's payload is `positions` (particles × 3 float32), `velocities` (the same, m/s: the VDB
/// export's `vel` grids), then `contacts` (records of 48 bytes: position and normal, 3 float32
/// each; surface A, surface B, triangle A, triangle B, particle, uint32 each, 0xFFFFFFFF for none;
/// kind, uint8: 0 edge–triangle, 1 particle–triangle, 2 corner; 3 zero bytes). With numpy alone:
///
///     header = np.dtype([("magic", "S8"), ("version", "<u4"), ("kind", "<u4"), ("frame", "<i4"),
///                        ("particles", "<u4"), ("count", "<u4"), ("scalar_bytes", "<u4"),
///                        ("time", "<f8"), ("payload_bytes", "<u8"), ("payload_crc", "<u4"),
///                        ("header_crc", "<u4"), ("zero", "<u8")])
///     contact = np.dtype([("position", "<f4", 3), ("normal", "<f4", 3), ("surface_a", "<u4"),
///                         ("surface_b", "<u4"), ("triangle_a", "<u4"), ("triangle_b", "<u4"),
///                         ("particle", "<u4"), ("kind", "u1"), ("zero", "V3")])
///     data = open(path, "rb").read()
///     h = np.frombuffer(data, header, count=1)[0]
///     positions = np.frombuffer(data, "<f4", h["particles"] * 3, 64).reshape(-1, 3)
///     velocities = np.frombuffer(data, "<f4", h["particles"] * 3, 64 + 12 * int(h["particles"]))
///     contacts = np.frombuffer(data, contact, h["count"], 64 + 24 * int(h["particles"]))
///
/// A checkpoint's payload is positions, velocities and the implicit integrator's warm start
/// (scalar_bytes each; the warm start's count is a uint32 before it: particles or 0), the plane
/// holds (uint32 count, then int32 each), the touching pairs (2 uint32 each), then one byte:
/// surfaces still tangled, 0 or 1, and the steps taken so far as a uint64.

#include <string>
#include <string_view>

#include "core/checkpoint.hpp"
#include "output/frame.hpp"

namespace softbake {

inline constexpr std::size_t kCacheHeaderBytes = 64;
inline constexpr std::size_t kCacheContactBytes = 48;

/// `frame` as a cache file's bytes, into `bytes` (its memory reused from frame to frame). The
/// simulation's numbers are float32 (the default build) and go in unchanged; a double build's are
/// rounded, which is why every writer is fed the decoded frame (cacheRoundTrip()).
void encodeCacheFrame(const Frame& frame, std::string& bytes);
std::string encodeCacheFrame(const Frame& frame);
/// Reads a cache frame into `frame`, reusing its vectors' memory. Throws softbake::Error starting
/// with `name` and saying what is wrong (not a cache file, another version or kind, a size that
/// does not add up, a checksum that does not match).
void decodeCacheFrame(std::string_view bytes, std::string_view name, Frame& frame);
Frame decodeCacheFrame(std::string_view bytes, std::string_view name);
/// Rounds `frame`'s numbers as the cache stores them (a no-op in the float32 build), so outputs
/// written now equal the ones `softbake export` writes later from the cache.
void roundToCachePrecision(Frame& frame);

std::string encodeCheckpoint(const SimulationCheckpoint& checkpoint, int frame, double time);
struct DecodedCheckpoint {
  int frame = 1;
  double time = 0;
  SimulationCheckpoint checkpoint;
};
/// As decodeCacheFrame; also refuses a checkpoint of the other precision.
DecodedCheckpoint decodeCheckpoint(std::string_view bytes, std::string_view name);

}  // namespace softbake
