#include "exporters/vdb_sequence_writer.hpp"

#include <unistd.h>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/points/PointConversion.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/PointIndexGrid.h>
#include <cmath>
#include <fstream>
#include <mutex>
#include <set>

#include "core/error.hpp"
#include "core/text.hpp"
#include "exporters/mesh_level_set.hpp"
#include "output/atomic_file.hpp"
#include "output/file_digest.hpp"
#include "output/finite_values.hpp"
#include "output/version.hpp"

namespace softbake {

namespace {

std::once_flag openvdbInitialized;

void initializeOpenVdb() {
  std::call_once(openvdbInitialized, [] { openvdb::initialize(); });
}

// Distinguishes temporary names of concurrent writers in one process; the pid separates processes.
std::atomic<unsigned long> temporaryCounter{0};

/// The up-axis rotation: identity for 'y', (x, y, z) -> (x, -z, y) for 'z'. Positions, velocities
/// and normals all go through it, so the grids stay consistent with each other.
openvdb::Vec3d toOutputAxes(const Vec3& v, char upAxis) {
  if (upAxis == 'z') return {double(v.x()), -double(v.z()), double(v.y())};
  return {double(v.x()), double(v.y()), double(v.z())};
}

std::uint64_t halfPhysicalMemory() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), pageSize = ::sysconf(_SC_PAGESIZE);
  if (pages <= 0 || pageSize <= 0) return std::uint64_t(4) << 30;  // unknown: assume 8 GiB
  return std::uint64_t(pages) * std::uint64_t(pageSize) / 2;
}

/// Surface area of every body at rest, in world units².
double restSurfaceArea(const SceneTopology& topology) {
  double area = 0;
  for (const Triangle& t : topology.triangles) {
    const Vec3d a = topology.restPosition[t[0]].cast<double>(),
                b = topology.restPosition[t[1]].cast<double>(),
                c = topology.restPosition[t[2]].cast<double>();
    area += 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

std::string sanitize(const std::string& name) {
  std::string out;
  for (char ch : name) {
    const bool keep = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') ||
                      (ch >= '0' && ch <= '9') || ch == '_';
    out += keep ? ch : '_';
  }
  return out.empty() ? "body" : out;
}

std::uint32_t compressionFlags(VdbOptions::Compression compression) {
  switch (compression) {
    case VdbOptions::Compression::Blosc:
      return openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK;
    case VdbOptions::Compression::Zip:
      return openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK;
    case VdbOptions::Compression::None:
      return openvdb::io::COMPRESS_NONE;
  }
  return openvdb::io::COMPRESS_ZIP;
}

}  // namespace

bool bloscAvailable() {
  initializeOpenVdb();
  return openvdb::io::Archive::hasBloscCompression();
}

double autoVoxelSize(const SceneTopology& topology) {
  double length = 0;
  std::size_t edges = 0;
  for (const Triangle& t : topology.triangles)
    for (int e = 0; e < 3; ++e) {
      length += (topology.restPosition[t[e]] - topology.restPosition[t[(e + 1) % 3]])
                    .cast<double>()
                    .norm();
      ++edges;
    }
  return edges == 0 ? 0.0 : 0.5 * length / double(edges);
}

void validate(const VdbOptions& options, const SceneTopology& topology) {
  const bool automatic = options.voxelSize == 0;
  if (!automatic && !(options.voxelSize > 0 && std::isfinite(options.voxelSize)))
    throw Error(cat("VDB voxel size ", options.voxelSize,
                    " is invalid: give a positive size in world units, or 0 for automatic"));
  if (!(options.bandWidth >= 1 && std::isfinite(options.bandWidth)))
    throw Error(cat("VDB narrow band of ", options.bandWidth,
                    " voxels is too narrow: a level set needs at least 1 (3 is usual)"));
  if (options.upAxis != 'y' && options.upAxis != 'z')
    throw Error(cat("VDB up axis '", options.upAxis, "' is invalid: use 'y' or 'z'"));
  if (options.compression == VdbOptions::Compression::Blosc && !bloscAvailable())
    throw Error("this OpenVDB build has no Blosc compression: use zip or none");
  if (!(options.fps > 0 && std::isfinite(options.fps)))
    throw Error(cat("VDB fps ", options.fps, " must be a positive number"));

  const double voxel = automatic ? autoVoxelSize(topology) : options.voxelSize;
  if (!(voxel > 0))
    throw Error("cannot derive a VDB voxel size: the bodies have no edges; give a voxel size");

  // The narrow band holds about (surface area / voxel²) × (2·band + 1) voxels. Per voxel: the
  // distance (4 bytes) and the mesher's per-leaf scratch (4), the velocity (12) and fog (4) when
  // asked, all doubled for partly filled leaves and the trees' own structure.
  const double bytesPerVoxel =
      2.0 * (8.0 + (options.velocity ? 12.0 : 0.0) + (options.fog ? 4.0 : 0.0));
  const double voxels = restSurfaceArea(topology) / (voxel * voxel) * (2 * options.bandWidth + 1);
  const double bytes = voxels * bytesPerVoxel;
  const double limit =
      double(options.memoryLimit != 0 ? options.memoryLimit : halfPhysicalMemory());
  if (bytes > limit) {
    const double fitting = voxel * std::sqrt(bytes / limit);
    throw Error(cat("VDB voxel size ", voxel, " would make about ", voxels, " narrow-band voxels (",
                    bytes / double(1 << 20), " MiB per frame, more than the limit of ",
                    limit / double(1 << 20), " MiB): use a voxel size of at least ", fitting,
                    " or a narrower band"));
  }
}

VdbSequenceWriter::VdbSequenceWriter(const SceneTopology& topology,
                                     const std::filesystem::path& outputDirectory,
                                     std::string scene, VdbOptions options, int framePadding)
    : outputDirectory_(outputDirectory),
      naming_{"vdb", std::move(scene), ".vdb", framePadding},
      options_(std::move(options)) {
  validate(options_, topology);
  initializeOpenVdb();
  voxelSize_ = options_.voxelSize == 0 ? autoVoxelSize(topology) : options_.voxelSize;
  particleCount_ = topology.particleCount();

  std::set<std::string> used;
  for (const Body& body : topology.bodies) {
    BodyData data;
    std::string unique = sanitize(body.name);
    for (int n = 2; !used.insert(unique).second; ++n) unique = cat(sanitize(body.name), "_", n);
    data.name = std::move(unique);
    data.firstParticle = body.firstParticle;
    data.particleCount = body.particleCount;
    std::vector<MeshLevelSet::TriangleIndices> triangles;
    triangles.reserve(body.triangleCount);
    for (Index t = body.firstTriangle; t < body.firstTriangle + body.triangleCount; ++t) {
      const Triangle& global = topology.triangles[t];
      triangles.push_back({std::uint32_t(global[0] - body.firstParticle),
                           std::uint32_t(global[1] - body.firstParticle),
                           std::uint32_t(global[2] - body.firstParticle)});
    }
    data.levelSet =
        std::make_shared<const MeshLevelSet>(std::move(triangles), body.particleCount, body.closed);
    bodies_.push_back(std::move(data));
  }
  makeDirectories(outputDirectory_ / naming_.folder);
}

std::filesystem::path VdbSequenceWriter::framePath(int frameNumber) const {
  return outputDirectory_ / naming_.relativePath(frameNumber);
}

OutputSequence VdbSequenceWriter::sequence() const {
  return {"vdb", naming_.pattern(), naming_.printfPattern(), {}};
}

std::string VdbSequenceWriter::gridName(std::size_t body, const std::string& kind) const {
  if (bodies_.size() == 1) return kind;
  return cat(bodies_[body].name, "_", kind);
}

namespace {

/// Copies every entry of `metadata` onto `grid`, and the body's name when there is one.
void addMetadata(openvdb::GridBase& grid, const openvdb::MetaMap& metadata,
                 const std::string& body) {
  for (auto it = metadata.beginMeta(); it != metadata.endMeta(); ++it)
    grid.insertMeta(it->first, *it->second);
  if (!body.empty()) grid.insertMeta("body", openvdb::StringMetadata(body));
}

/// The frame's contacts as a PointDataGrid named `contacts`: position, `N` and `body`.
openvdb::GridBase::Ptr contactGrid(const std::vector<Contact>& frameContacts, char up,
                                   const openvdb::math::Transform& transform) {
  std::vector<openvdb::Vec3f> positions, normals;
  std::vector<openvdb::Int32> surfaces;
  for (const Contact& c : frameContacts) {
    positions.emplace_back(toOutputAxes(c.position, up));
    normals.emplace_back(toOutputAxes(c.normal, up));
    surfaces.push_back(openvdb::Int32(c.surfaceA));
  }
  namespace points_ = openvdb::points;
  const points_::PointAttributeVector<openvdb::Vec3f> positionArray(positions);
  auto pointIndex = openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(
      positionArray, transform);
  auto contacts = points_::createPointDataGrid<points_::NullCodec, points_::PointDataGrid>(
      *pointIndex, positionArray, transform);
  points_::appendAttribute<openvdb::Vec3f>(contacts->tree(), "N");
  points_::populateAttribute(contacts->tree(), pointIndex->tree(), "N",
                             points_::PointAttributeVector<openvdb::Vec3f>(normals));
  points_::appendAttribute<openvdb::Int32>(contacts->tree(), "body");
  points_::populateAttribute(contacts->tree(), pointIndex->tree(), "body",
                             points_::PointAttributeVector<openvdb::Int32>(surfaces));
  contacts->setName("contacts");
  return contacts;
}

/// OpenVDB stamps every file it writes with a random UUID, so the same frame written twice differs
/// in 36 bytes; a resumed or exported run could not then reproduce a run's files. The UUID becomes
/// one derived from the rest of the file instead (version 8, RFC 9562's custom kind): the same
/// grids, the same bytes. Throws softbake::Error naming `path` when the header is not the one
/// OpenVDB 10 writes.
void stampContentUuid(const std::filesystem::path& temporary, const std::filesystem::path& path) {
  // magic (8 bytes), file version, library major and minor (4 each), has-grid-offsets (1), then
  // the UUID as 36 characters.
  constexpr std::size_t kUuidOffset = 21, kUuidLength = 36;
  std::string bytes;
  {
    std::ifstream in(temporary, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  if (bytes.size() < kUuidOffset + kUuidLength || bytes[kUuidOffset + 8] != '-' ||
      bytes[kUuidOffset + 23] != '-')
    throw OutputFailure(
        cat("cannot write '", path.string(),
            "': OpenVDB wrote a header without its UUID where softbake expects it"));
  const std::string digest = sha256(std::string_view(bytes).substr(kUuidOffset + kUuidLength));
  static constexpr char kHex[] = "0123456789abcdef";
  char uuid[kUuidLength];
  for (std::size_t i = 0, nibble = 0; i < kUuidLength; ++i) {
    if (i == 8 || i == 13 || i == 18 || i == 23) {
      uuid[i] = '-';
      continue;
    }
    const std::uint8_t byte = std::uint8_t(digest[nibble / 2]);
    uuid[i] = kHex[nibble % 2 == 0 ? byte >> 4 : byte & 15];
    ++nibble;
  }
  uuid[14] = '8';                                      // the version
  uuid[19] = kHex[8 | (std::uint8_t(digest[8]) & 3)];  // the RFC variant, 10xx
  std::fstream out(temporary, std::ios::binary | std::ios::in | std::ios::out);
  out.seekp(std::streamoff(kUuidOffset));
  out.write(uuid, kUuidLength);
  out.close();
  if (!out)
    throw OutputFailure(cat("cannot write '", path.string(), "': rewriting its UUID failed"));
}

/// Writes `grids` to `path` under a temporary name and renames it, so readers never see a torn
/// file. Returns the file's size.
std::uintmax_t writeGridsAtomically(const std::filesystem::path& path,
                                    const openvdb::GridPtrVec& grids,
                                    const openvdb::MetaMap& metadata, std::uint32_t compression) {
  const std::filesystem::path temporary =
      path.parent_path() / cat(".", path.filename().string(), ".tmp-", long(::getpid()), "-",
                               temporaryCounter.fetch_add(1, std::memory_order_relaxed));
  try {
    openvdb::io::File file(temporary.string());
    file.setCompression(compression);
    file.write(grids, metadata);
    file.close();
  } catch (const std::exception& e) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw OutputFailure(cat("cannot write '", path.string(), "': ", e.what()));
  }
  try {
    stampContentUuid(temporary, path);
  } catch (const Error&) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw;
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw OutputFailure(
        cat("cannot write '", path.string(), "': rename failed: ", error.message()));
  }
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  return error ? 0 : size;
}

}  // namespace

void VdbSequenceWriter::write(const Frame& frame) {
  if (frame.positions.size() < particleCount_)
    throw Error(cat("frame ", frame.number, " has ", frame.positions.size(),
                    " particle positions; the scene has ", particleCount_));
  if (options_.velocity && frame.velocities.size() != frame.positions.size())
    throw Error(cat("frame ", frame.number, " has ", frame.velocities.size(),
                    " particle velocities for ", frame.positions.size(),
                    " positions: the VDB `vel` grid needs one per particle"));

  const std::filesystem::path path = framePath(frame.number);
  requireFinite(path, frame.time, [&] { return cat("frame ", frame.number, ": the time"); });

  openvdb::MetaMap metadata;
  metadata.insertMeta("frame", openvdb::Int32Metadata(frame.number));
  metadata.insertMeta("time", openvdb::DoubleMetadata(frame.time));
  metadata.insertMeta("fps", openvdb::DoubleMetadata(options_.fps));
  metadata.insertMeta("scene", openvdb::StringMetadata(naming_.scene));
  metadata.insertMeta("softbake_version", openvdb::StringMetadata(softbakeVersion()));
  metadata.insertMeta("units", openvdb::StringMetadata(options_.units));

  const char up = options_.upAxis;
  openvdb::GridPtrVec grids;
  std::vector<openvdb::Vec3s> points, velocities;  // points in index space
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    const BodyData& body = bodies_[b];
    points.resize(body.particleCount);
    for (Index i = 0; i < body.particleCount; ++i) {
      const Vec3& p = frame.positions[body.firstParticle + i];
      requireFinite(path, p, [&] {
        return cat("frame ", frame.number, ": body '", body.name, "': the position of particle ",
                   i);
      });
      points[i] = openvdb::Vec3s(toOutputAxes(p, up) / voxelSize_);
    }
    if (options_.velocity) {
      velocities.resize(body.particleCount);
      for (Index i = 0; i < body.particleCount; ++i) {
        const Vec3& v = frame.velocities[body.firstParticle + i];
        requireFinite(path, v, [&] {
          return cat("frame ", frame.number, ": body '", body.name, "': the velocity of particle ",
                     i);
        });
        velocities[i] = openvdb::Vec3s(toOutputAxes(v, up));
      }
    }
    MeshLevelSet::Grids level =
        body.levelSet->build(points, options_.velocity ? velocities.data() : nullptr,
                             float(options_.bandWidth), voxelSize_);

    openvdb::FloatGrid::Ptr surface = level.distance;
    surface->setName(gridName(b, body.levelSet->closed() ? "surface" : "surface_udf"));
    addMetadata(*surface, metadata, body.name);
    grids.push_back(surface);

    if (options_.fog && body.levelSet->closed()) {
      openvdb::FloatGrid::Ptr fog = surface->deepCopy();
      openvdb::tools::sdfToFogVolume(*fog);
      fog->setName(gridName(b, "density"));
      grids.push_back(fog);
    }

    if (level.velocity) {
      level.velocity->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
      level.velocity->setName(gridName(b, "vel"));
      addMetadata(*level.velocity, metadata, body.name);
      grids.push_back(level.velocity);
    }
  }
  if (options_.contacts && !frame.contacts.empty()) {
    requireFiniteContacts(path, frame, [](std::size_t i) { return cat("contact ", i); });
    const openvdb::math::Transform::Ptr transform =
        openvdb::math::Transform::createLinearTransform(voxelSize_);
    openvdb::GridBase::Ptr contacts = contactGrid(frame.contacts, up, *transform);
    addMetadata(*contacts, metadata, "");
    grids.push_back(contacts);
  }
  const std::uintmax_t size =
      writeGridsAtomically(path, grids, metadata, compressionFlags(options_.compression));
  bytes_.fetch_add(size, std::memory_order_relaxed);
}

}  // namespace softbake
