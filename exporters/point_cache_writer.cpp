#include "exporters/point_cache_writer.hpp"

#include <unistd.h>

#include <bit>
#include <charconv>
#include <cstring>
#include <set>

#include "core/error.hpp"
#include "core/text.hpp"
#include "exporters/texcoord_table.hpp"
#include "output/atomic_file.hpp"
#include "output/finite_values.hpp"

namespace softbake {

namespace {

std::atomic<unsigned long> temporaryCounter{0};

Vec3f toAxes(const Vec3& v, char upAxis) {
  const Vec3f f = v.cast<float>();
  return upAxis == 'z' ? Vec3f(f.x(), -f.z(), f.y()) : f;
}

std::string safeName(const std::string& text) {
  std::string name = text;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-' && c != '_') c = '_';
  return name;
}

void appendNumber(std::string& out, float value) {
  char digits[32];
  out.append(digits, std::to_chars(digits, digits + sizeof digits, value).ptr);
}

/// The host's float as the file's bytes: PC2 is little-endian, MDD big-endian.
std::uint32_t fileOrder(float value, PointCacheFormat format) {
  const auto bits = std::bit_cast<std::uint32_t>(value);
  return format == PointCacheFormat::Mdd ? __builtin_bswap32(bits) : bits;
}
std::uint32_t fileOrder(std::int32_t value, PointCacheFormat format) {
  const auto bits = std::uint32_t(value);
  return format == PointCacheFormat::Mdd ? __builtin_bswap32(bits) : bits;
}

static_assert(std::endian::native == std::endian::little, "PC2 is written as the host holds it");

}  // namespace

std::vector<std::string> pointCacheStems(const SceneTopology& topology, const std::string& scene) {
  std::vector<std::string> stems;
  std::set<std::string> used;
  for (const Body& body : topology.bodies) {
    const std::string base = safeName(scene + "_" + body.name);
    std::string stem = base;
    for (int n = 2; !used.insert(stem).second; ++n) stem = cat(base, "_", n);
    stems.push_back(stem);
  }
  return stems;
}

void writeRestMeshes(const SceneTopology& topology, const std::filesystem::path& outputDirectory,
                     const std::string& scene, char upAxis) {
  const std::filesystem::path folder = outputDirectory / "cache_mesh";
  makeDirectories(folder);
  const std::vector<std::string> stems = pointCacheStems(topology, scene);
  for (std::size_t b = 0; b < topology.bodies.size(); ++b) {
    const Body& body = topology.bodies[b];
    const std::filesystem::path path = folder / (stems[b] + ".obj");
    std::string text = cat("# softbake rest mesh of body '", body.name, "' of scene '", scene,
                           "': vertices in particle order, as the point caches hold them\n", "o ",
                           safeName(body.name), "\n");
    for (Index i = 0; i < body.particleCount; ++i) {
      const Vec3& p = topology.restPosition[body.firstParticle + i];
      requireFinite(path, p, [&] { return cat("body '", body.name, "': particle ", i); });
      const Vec3f v = toAxes(p, upAxis);
      text += "v ";
      for (int k = 0; k < 3; ++k) {
        appendNumber(text, v[k]);
        text += k < 2 ? ' ' : '\n';
      }
    }
    const TexcoordTable texcoords = texcoordTable(body.render);
    for (const Vec2f& uv : texcoords.uvs) {
      text += "vt ";
      appendNumber(text, uv.x());
      text += ' ';
      appendNumber(text, uv.y());
      text += '\n';
    }
    const bool hasUvs = !texcoords.uvs.empty();
    const std::span<const Triangle> triangles = topology.bodyTriangles(body);
    for (std::size_t t = 0; t < triangles.size(); ++t) {
      text += 'f';
      for (int corner = 0; corner < 3; ++corner) {
        text += cat(' ', triangles[t][corner] - body.firstParticle + 1);
        if (hasUvs) text += cat('/', texcoords.corners[t][corner] + 1);
      }
      text += '\n';
    }
    writeFileAtomically(path, text);
  }
}

PointCacheWriter::PointCacheWriter(std::shared_ptr<const SceneTopology> topology,
                                   const std::filesystem::path& outputDirectory, std::string scene,
                                   PointCacheFormat format, int frames, double fps, char upAxis)
    : topology_(std::move(topology)),
      outputDirectory_(outputDirectory),
      format_(format),
      frames_(frames),
      fps_(fps),
      upAxis_(upAxis),
      stems_(pointCacheStems(*topology_, scene)) {
  makeDirectories(outputDirectory_ / name());
}

PointCacheWriter::~PointCacheWriter() {
  closeAndRemoveTemporaries();
}

std::vector<PointCacheFiles> PointCacheWriter::files() const {
  std::vector<PointCacheFiles> files;
  for (std::size_t b = 0; b < stems_.size(); ++b)
    files.push_back({topology_->bodies[b].name, cat("cache_mesh/", stems_[b], ".obj"),
                     cat(name(), "/", stems_[b], ".", name())});
  return files;
}

void PointCacheWriter::closeAndRemoveTemporaries() {
  for (Stream& stream : streams_) {
    if (stream.file) std::fclose(stream.file);
    stream.file = nullptr;
    std::error_code ignored;
    if (!stream.temporary.empty()) std::filesystem::remove(stream.temporary, ignored);
  }
  streams_.clear();
}

void PointCacheWriter::write(const Frame& frame) {
  if (streams_.empty()) {
    // Opened by the first frame, headers written with the counts of a complete run.
    const std::vector<PointCacheFiles> files = this->files();
    for (std::size_t b = 0; b < stems_.size(); ++b) {
      Stream stream;
      stream.path = outputDirectory_ / files[b].cache;
      stream.temporary = stream.path.parent_path() /
                         cat(".", stream.path.filename().string(), ".tmp-", long(::getpid()), "-",
                             temporaryCounter.fetch_add(1, std::memory_order_relaxed));
      stream.file = std::fopen(stream.temporary.c_str(), "wbx");
      if (!stream.file)
        throw OutputFailure(
            cat("cannot write '", stream.path.string(), "': ", std::strerror(errno)));
      streams_.push_back(stream);
    }
    for (std::size_t b = 0; b < stems_.size(); ++b) {
      const auto points = std::int32_t(topology_->bodies[b].particleCount);
      std::vector<std::uint32_t> header;
      if (format_ == PointCacheFormat::Pc2) {
        char magic[12] = "POINTCACHE2";
        std::fwrite(magic, 1, sizeof magic, streams_[b].file);
        header = {fileOrder(1, format_), fileOrder(points, format_), fileOrder(1.0f, format_),
                  fileOrder(1.0f, format_), fileOrder(std::int32_t(frames_), format_)};
      } else {
        header = {fileOrder(std::int32_t(frames_), format_), fileOrder(points, format_)};
        for (int f = 1; f <= frames_; ++f)
          header.push_back(fileOrder(float((f - 1) / fps_), format_));
      }
      std::fwrite(header.data(), 4, header.size(), streams_[b].file);
    }
  }
  if (frame.number != nextFrame_)
    throw OutputFailure(cat("cannot write '", streams_.front().path.string(), "': frame ",
                            frame.number, " arrived where frame ", nextFrame_,
                            " belongs (point caches are written in "
                            "order)"));
  if (nextFrame_ > frames_)
    throw OutputFailure(cat("cannot write '", streams_.front().path.string(), "': frame ",
                            frame.number, " is past the ", frames_, " frames of its header"));
  for (std::size_t b = 0; b < stems_.size(); ++b) {
    const Body& body = topology_->bodies[b];
    const Stream& stream = streams_[b];
    buffer_.resize(std::size_t(body.particleCount) * 3);
    for (Index i = 0; i < body.particleCount; ++i) {
      const Vec3& p = frame.positions[body.firstParticle + i];
      requireFinite(stream.path, p, [&] {
        return cat("frame ", frame.number, ": body '", body.name, "': particle ", i);
      });
      const Vec3f v = toAxes(p, upAxis_);
      for (int k = 0; k < 3; ++k)
        buffer_[std::size_t(i) * 3 + std::size_t(k)] =
            std::bit_cast<float>(fileOrder(v[k], format_));
    }
    if (std::fwrite(buffer_.data(), 4, buffer_.size(), stream.file) != buffer_.size())
      throw OutputFailure(cat("cannot write '", stream.path.string(), "': ", std::strerror(errno)));
    bytes_.fetch_add(buffer_.size() * 4, std::memory_order_relaxed);
  }
  ++nextFrame_;
}

void PointCacheWriter::finish() {
  if (nextFrame_ != frames_ + 1) {  // a stopped run: no part-written cache under its name
    closeAndRemoveTemporaries();
    return;
  }
  for (Stream& stream : streams_) {
    // The header's counts were written for a complete run, and it is complete: only close.
    const bool flushed = std::fflush(stream.file) == 0;
    const int error = errno;
    const bool closed = std::fclose(stream.file) == 0;
    stream.file = nullptr;
    if (!flushed || !closed)
      throw OutputFailure(cat("cannot write '", stream.path.string(), "': ", std::strerror(error)));
    std::error_code renamed;
    std::filesystem::rename(stream.temporary, stream.path, renamed);
    if (renamed)
      throw Error(
          cat("cannot write '", stream.path.string(), "': rename failed: ", renamed.message()));
    stream.temporary.clear();
  }
  streams_.clear();
}

}  // namespace softbake
