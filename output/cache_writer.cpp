#include "output/cache_writer.hpp"

#include <cmath>
#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/text.hpp"
#include "output/atomic_file.hpp"

namespace softbake {

namespace {

/// The whole file into `bytes` (its memory reused). Throws softbake::Error naming the file.
void readFileInto(const std::filesystem::path& path, std::string& bytes) {
  const std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw Error(cat(path.string(), ": cannot read the cache file"));
  bytes.clear();
  char chunk[1 << 16];
  std::size_t read = 0;
  while ((read = std::fread(chunk, 1, sizeof chunk, file.get())) > 0) bytes.append(chunk, read);
  if (std::ferror(file.get())) throw Error(cat(path.string(), ": cannot read the cache file"));
}

}  // namespace

CacheLayout::CacheLayout(std::filesystem::path outputDirectory, std::string scene, int framePadding)
    : outputDirectory_(std::move(outputDirectory)),
      frames_{"cache", scene, ".sbframe", framePadding},
      checkpoints_{"cache", std::move(scene), ".sbcheckpoint", framePadding} {}

std::filesystem::path CacheLayout::framePath(int frameNumber) const {
  return outputDirectory_ / frames_.relativePath(frameNumber);
}

std::filesystem::path CacheLayout::checkpointPath(int frameNumber) const {
  return outputDirectory_ / checkpoints_.relativePath(frameNumber);
}

std::filesystem::path CacheLayout::indexPath() const {
  return directory() / "index.json";
}

std::filesystem::path CacheLayout::directory() const {
  return outputDirectory_ / frames_.folder;
}

std::optional<DecodedCheckpoint> CacheLayout::latestCheckpoint(
    int frame, std::vector<std::string>* skipped) const {
  std::string bytes;
  for (int candidate = frame; candidate > 1; --candidate) {
    const std::filesystem::path path = checkpointPath(candidate);
    std::error_code missing;
    if (!std::filesystem::exists(path, missing)) continue;
    try {
      readFileInto(path, bytes);
      DecodedCheckpoint checkpoint = decodeCheckpoint(bytes, path.string());
      if (checkpoint.frame != candidate)
        throw Error(cat(path.string(), ": holds frame ", checkpoint.frame));
      return checkpoint;
    } catch (const Error& error) {
      if (skipped) skipped->push_back(error.what());
    }
  }
  return std::nullopt;
}

void CacheLayout::readFrame(int frameNumber, Frame& frame) const {
  const std::filesystem::path path = framePath(frameNumber);
  std::error_code missing;
  if (!std::filesystem::exists(path, missing))
    throw Error(cat(path.string(), ": the cache has no frame ", frameNumber,
                    " (was the run made with --no-cache, or is it incomplete?)"));
  thread_local std::string bytes;
  readFileInto(path, bytes);
  decodeCacheFrame(bytes, path.string(), frame);
  if (frame.number != frameNumber)
    throw Error(cat(path.string(), ": holds frame ", frame.number, ", not ", frameNumber));
}

Eigen::AlignedBox3f CacheLayout::shotBounds(int frames) const {
  Eigen::AlignedBox3f bounds;
  Frame frame;
  for (int number = 1; number <= frames; ++number) {
    readFrame(number, frame);
    for (const Vec3& p : frame.positions) bounds.extend(p.cast<float>());
  }
  return bounds;
}

bool isCheckpointFrame(int frame, int every) {
  return every > 0 && frame > 1 && (frame - 1) % every == 0;
}

int defaultCheckpointInterval(std::size_t checkpointBytes, std::size_t frameBytes) {
  if (frameBytes == 0) return 1;
  // A checkpoint every N frames costs checkpointBytes / (N · frameBytes) of the cache.
  return std::max(1, int(std::ceil(10.0 * double(checkpointBytes) / double(frameBytes))));
}

CacheWriter::CacheWriter(const std::filesystem::path& outputDirectory, std::string scene,
                         int framePadding, int frames, int checkpointEvery, std::size_t particles)
    : layout_(outputDirectory, scene, framePadding),
      scene_(std::move(scene)),
      frames_(frames),
      checkpointEvery_(checkpointEvery),
      particles_(particles) {
  makeDirectories(layout_.directory());
}

void CacheWriter::write(const Frame& frame) {
  encodeCacheFrame(frame, buffer_);
  writeFileAtomically(layout_.framePath(frame.number), buffer_, Durability::PowerLoss);
  bytes_.fetch_add(buffer_.size(), std::memory_order_relaxed);
  if (frame.hasCheckpoint) {
    const std::string checkpoint = encodeCheckpoint(frame.checkpoint, frame.number, frame.time);
    writeFileAtomically(layout_.checkpointPath(frame.number), checkpoint, Durability::PowerLoss);
    bytes_.fetch_add(checkpoint.size(), std::memory_order_relaxed);
  }
}

std::string CacheWriter::indexJson() const {
  using Json = nlohmann::ordered_json;
  Json checkpoints = Json::array();
  for (int frame = 2; frame <= frames_; ++frame)
    if (isCheckpointFrame(frame, checkpointEvery_)) checkpoints.push_back(frame);
  const Json json = {{"format", "softbake cache"},
                     {"version", 1},
                     {"scene", scene_},
                     {"particles", particles_},
                     {"first_frame", 1},
                     {"last_frame", frames_},
                     {"frame_pattern", layout_.frameNaming().pattern()},
                     {"checkpoint_pattern", layout_.checkpointNaming().pattern()},
                     {"checkpoint_every", checkpointEvery_},
                     {"checkpoints", std::move(checkpoints)}};
  return json.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

void CacheWriter::finish() {
  writeFileAtomically(layout_.indexPath(), indexJson(), Durability::PowerLoss);
}

OutputSequence CacheWriter::sequence() const {
  const FrameNaming& naming = layout_.frameNaming();
  return {"cache", naming.pattern(), naming.printfPattern(), {"cache/index.json"}};
}

}  // namespace softbake
