#include "output/cache_format.hpp"

#include <zlib.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "core/error.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

static_assert(std::endian::native == std::endian::little,
              "the cache is little-endian and written as the processor holds its numbers");

constexpr char kMagic[8] = {'S', 'B', 'C', 'A', 'C', 'H', 'E', '\0'};
constexpr std::uint32_t kVersion = 1;
constexpr std::uint32_t kFrameKind = 1, kCheckpointKind = 2;
constexpr std::size_t kHeaderCrcBytes = 52;  ///< the header's bytes its own checksum covers

std::uint32_t crc32Of(std::string_view bytes) {
  return std::uint32_t(
      crc32_z(crc32_z(0, Z_NULL, 0), reinterpret_cast<const Bytef*>(bytes.data()), bytes.size()));
}

class ByteWriter {
 public:
  template <class T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof value);
  }
  void putVectors(const std::vector<Vec3>& vectors) {
    for (const Vec3& v : vectors)
      for (int k = 0; k < 3; ++k) put(v[k]);
  }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

class ByteReader {
 public:
  ByteReader(std::string_view bytes, std::string_view name) : bytes_(bytes), name_(name) {}
  template <class T>
  T get(std::string_view what) {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T), what);
    T value;
    std::memcpy(&value, bytes_.data() + at_, sizeof value);
    at_ += sizeof value;
    return value;
  }
  Vec3 getFloat3(std::string_view what) {
    Vec3 v;
    for (int k = 0; k < 3; ++k) v[k] = Scalar(get<float>(what));
    return v;
  }
  void getVectors(std::vector<Vec3>& vectors, std::size_t count, std::string_view what) {
    need(count * sizeof(Vec3), what);
    vectors.resize(count);
    for (Vec3& v : vectors)
      for (int k = 0; k < 3; ++k) v[k] = get<Scalar>(what);
  }
  void expectEnd() const {
    if (at_ != bytes_.size())
      throw Error(cat(name_, ": ", bytes_.size() - at_, " bytes past the end of the cache record"));
  }

 private:
  void need(std::size_t count, std::string_view what) const {
    if (bytes_.size() - at_ < count)
      throw Error(cat(name_, ": the cache file ends inside its ", what));
  }
  std::string_view bytes_;
  std::string_view name_;
  std::size_t at_ = 0;
};

struct Header {
  std::uint32_t kind = 0;
  std::int32_t frame = 1;
  std::uint32_t particles = 0, count = 0, scalarBytes = 0;
  double time = 0;
};

/// The 64 header bytes for `payload`.
std::string headerBytes(const Header& header, std::string_view payload) {
  ByteWriter out;
  out.bytes().append(kMagic, sizeof kMagic);
  out.put(kVersion);
  out.put(header.kind);
  out.put(header.frame);
  out.put(header.particles);
  out.put(header.count);
  out.put(header.scalarBytes);
  out.put(header.time);
  out.put(std::uint64_t(payload.size()));
  out.put(crc32Of(payload));
  out.put(crc32Of(std::string_view(out.bytes()).substr(0, kHeaderCrcBytes)));
  out.put(std::uint64_t(0));
  return std::move(out.bytes());
}

/// The header for `payload`, then the payload.
std::string withHeader(const Header& header, std::string_view payload) {
  return headerBytes(header, payload).append(payload);
}

/// Checks the header of `bytes` and returns it; the payload follows at kCacheHeaderBytes.
Header readHeader(std::string_view bytes, std::string_view name, std::uint32_t kind) {
  if (bytes.size() < kCacheHeaderBytes || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    throw Error(cat(name, ": not a softbake cache file (no SBCACHE header)"));
  ByteReader in(bytes.substr(sizeof kMagic, kCacheHeaderBytes - sizeof kMagic), name);
  const auto version = in.get<std::uint32_t>("header");
  if (version != kVersion)
    throw Error(cat(name, ": cache format version ", version, ", this softbake reads ", kVersion));
  Header header;
  header.kind = in.get<std::uint32_t>("header");
  header.frame = in.get<std::int32_t>("header");
  header.particles = in.get<std::uint32_t>("header");
  header.count = in.get<std::uint32_t>("header");
  header.scalarBytes = in.get<std::uint32_t>("header");
  header.time = in.get<double>("header");
  const auto payloadBytes = in.get<std::uint64_t>("header");
  const auto payloadCrc = in.get<std::uint32_t>("header");
  const auto headerCrc = in.get<std::uint32_t>("header");
  if (in.get<std::uint64_t>("header") != 0)
    throw Error(cat(name, ": the cache file's header has bytes 56-63 set, which are zero"));
  if (headerCrc != crc32Of(bytes.substr(0, kHeaderCrcBytes)))
    throw Error(cat(name, ": the cache file's header does not match its checksum"));
  if (header.kind != kind)
    throw Error(cat(name, ": a cache ", header.kind == kFrameKind ? "frame" : "checkpoint",
                    " where a ", kind == kFrameKind ? "frame" : "checkpoint", " was expected"));
  if (payloadBytes != bytes.size() - kCacheHeaderBytes)
    throw Error(cat(name, ": the header says ", payloadBytes, " bytes of data, the file holds ",
                    bytes.size() - kCacheHeaderBytes, " (cut short or appended to)"));
  if (payloadCrc != crc32Of(bytes.substr(kCacheHeaderBytes)))
    throw Error(cat(name, ": the cache file's data does not match its checksum"));
  return header;
}

}  // namespace

void encodeCacheFrame(const Frame& frame, std::string& bytes) {
  const std::size_t particles = frame.positions.size();
  if (frame.velocities.size() != particles)
    throw Error(cat("frame ", frame.number, ": ", frame.velocities.size(), " velocities for ",
                    particles, " particles"));
  // Sized once and filled in place: a frame of a million particles is 24 MB, so appending float
  // by float would spend more time growing the string than writing the file.
  bytes.resize(kCacheHeaderBytes + particles * 24 + frame.contacts.size() * kCacheContactBytes);
  char* out = bytes.data() + kCacheHeaderBytes;
  const auto put = [&out](auto value) {
    std::memcpy(out, &value, sizeof value);
    out += sizeof value;
  };
  const auto putVectors = [&](const std::vector<Vec3>& vectors) {
    if constexpr (std::is_same_v<Scalar, float> && sizeof(Vec3) == 12) {
      std::memcpy(out, vectors.data(), vectors.size() * 12);
      out += vectors.size() * 12;
    } else {
      for (const Vec3& v : vectors)
        for (int k = 0; k < 3; ++k) put(float(v[k]));
    }
  };
  putVectors(frame.positions);
  putVectors(frame.velocities);
  for (const Contact& contact : frame.contacts) {
    for (int k = 0; k < 3; ++k) put(float(contact.position[k]));
    for (int k = 0; k < 3; ++k) put(float(contact.normal[k]));
    for (const Index index : {contact.surfaceA, contact.surfaceB, contact.triangleA,
                              contact.triangleB, contact.particle})
      put(std::uint32_t(index));
    put(std::uint8_t(contact.kind));
    for (int zero = 0; zero < 3; ++zero) put(std::uint8_t(0));
  }
  const Header header{kFrameKind,
                      frame.number,
                      std::uint32_t(particles),
                      std::uint32_t(frame.contacts.size()),
                      std::uint32_t(sizeof(float)),
                      frame.time};
  const std::string head = headerBytes(header, std::string_view(bytes).substr(kCacheHeaderBytes));
  std::memcpy(bytes.data(), head.data(), kCacheHeaderBytes);
}

std::string encodeCacheFrame(const Frame& frame) {
  std::string bytes;
  encodeCacheFrame(frame, bytes);
  return bytes;
}

void decodeCacheFrame(std::string_view bytes, std::string_view name, Frame& frame) {
  const Header header = readHeader(bytes, name, kFrameKind);
  const std::uint64_t expected = std::uint64_t(header.particles) * 6 * sizeof(float) +
                                 std::uint64_t(header.count) * kCacheContactBytes;
  if (header.scalarBytes != sizeof(float) || expected != bytes.size() - kCacheHeaderBytes)
    throw Error(cat(name, ": ", header.particles, " particles and ", header.count,
                    " contacts do not make the ", bytes.size() - kCacheHeaderBytes,
                    " bytes of data"));
  ByteReader in(bytes.substr(kCacheHeaderBytes), name);
  frame.number = header.frame;
  frame.time = header.time;
  frame.positions.resize(header.particles);
  for (Vec3& p : frame.positions) p = in.getFloat3("positions");
  frame.velocities.resize(header.particles);
  for (Vec3& v : frame.velocities) v = in.getFloat3("velocities");
  frame.contacts.resize(header.count);
  for (std::uint32_t c = 0; c < header.count; ++c) {
    Contact& contact = frame.contacts[c];
    contact.position = in.getFloat3("contacts");
    contact.normal = in.getFloat3("contacts");
    contact.surfaceA = in.get<std::uint32_t>("contacts");
    contact.surfaceB = in.get<std::uint32_t>("contacts");
    contact.triangleA = in.get<std::uint32_t>("contacts");
    contact.triangleB = in.get<std::uint32_t>("contacts");
    contact.particle = in.get<std::uint32_t>("contacts");
    const auto kind = in.get<std::uint8_t>("contacts");
    if (kind > std::uint8_t(ContactKind::Held))
      throw Error(cat(name, ": contact ", c, " is of unknown kind ", int(kind)));
    contact.kind = ContactKind(kind);
    for (int zero = 0; zero < 3; ++zero) in.get<std::uint8_t>("contacts");
  }
  in.expectEnd();
}

Frame decodeCacheFrame(std::string_view bytes, std::string_view name) {
  Frame frame;
  decodeCacheFrame(bytes, name, frame);
  return frame;
}

void roundToCachePrecision(Frame& frame) {
  if constexpr (!std::is_same_v<Scalar, float>) {
    const auto round = [](Vec3& v) { v = v.cast<float>().cast<Scalar>(); };
    for (Vec3& p : frame.positions) round(p);
    for (Vec3& v : frame.velocities) round(v);
    for (Contact& contact : frame.contacts) {
      round(contact.position);
      round(contact.normal);
    }
  }
}

std::string encodeCheckpoint(const SimulationCheckpoint& checkpoint, int frame, double time) {
  ByteWriter payload;
  payload.putVectors(checkpoint.state.position);
  payload.putVectors(checkpoint.state.velocity);
  payload.put(std::uint32_t(checkpoint.warmStart.size()));
  payload.putVectors(checkpoint.warmStart);
  payload.put(std::uint32_t(checkpoint.planeHolds.size()));
  for (const std::int32_t plane : checkpoint.planeHolds) payload.put(plane);
  for (const TrianglePair& pair : checkpoint.touchingPairs) {
    payload.put(std::uint32_t(pair.first));
    payload.put(std::uint32_t(pair.second));
  }
  payload.put(std::uint8_t(checkpoint.tangled));
  payload.put(std::uint64_t(checkpoint.stepsTaken));
  Header header{kCheckpointKind,
                frame,
                std::uint32_t(checkpoint.state.position.size()),
                std::uint32_t(checkpoint.touchingPairs.size()),
                std::uint32_t(sizeof(Scalar)),
                time};
  return withHeader(header, payload.bytes());
}

DecodedCheckpoint decodeCheckpoint(std::string_view bytes, std::string_view name) {
  const Header header = readHeader(bytes, name, kCheckpointKind);
  if (header.scalarBytes != sizeof(Scalar))
    throw Error(cat(name, ": a checkpoint of ", header.scalarBytes * 8,
                    "-bit numbers; this softbake simulates in ", sizeof(Scalar) * 8, "-bit"));
  ByteReader in(bytes.substr(kCacheHeaderBytes), name);
  DecodedCheckpoint decoded;
  decoded.frame = header.frame;
  decoded.time = header.time;
  SimulationCheckpoint& checkpoint = decoded.checkpoint;
  in.getVectors(checkpoint.state.position, header.particles, "positions");
  in.getVectors(checkpoint.state.velocity, header.particles, "velocities");
  const auto warmStart = in.get<std::uint32_t>("warm start");
  if (warmStart != 0 && warmStart != header.particles)
    throw Error(
        cat(name, ": a warm start of ", warmStart, " for ", header.particles, " particles"));
  in.getVectors(checkpoint.warmStart, warmStart, "warm start");
  const auto holds = in.get<std::uint32_t>("plane holds");
  if (holds != 0 && holds != header.particles)
    throw Error(cat(name, ": ", holds, " plane holds for ", header.particles, " particles"));
  checkpoint.planeHolds.resize(holds);
  for (std::int32_t& plane : checkpoint.planeHolds) plane = in.get<std::int32_t>("plane holds");
  checkpoint.touchingPairs.resize(header.count);
  for (TrianglePair& pair : checkpoint.touchingPairs) {
    pair.first = in.get<std::uint32_t>("touching pairs");
    pair.second = in.get<std::uint32_t>("touching pairs");
  }
  checkpoint.tangled = in.get<std::uint8_t>("end") != 0;
  checkpoint.stepsTaken = in.get<std::uint64_t>("end");
  in.expectEnd();
  return decoded;
}

}  // namespace softbake
