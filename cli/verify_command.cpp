#include "cli/verify_command.hpp"

#include <cstdio>
#include <fstream>
#include <map>
#include <set>

#include "bake/command_errors.hpp"
#include "core/error.hpp"
#include "core/text.hpp"
#include "output/cache_format.hpp"
#include "output/manifest.hpp"

namespace softbake {

namespace {

namespace fs = std::filesystem;

/// The whole file, or an empty optional when it cannot be read to its end.
std::optional<std::string> readAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) return std::nullopt;
  return bytes;
}

/// Problems with `sequence` in `out`: frames missing, empty, unreadable or damaged, frames twice
/// (under another padding), frames past the run's, temporary files of a killed writer.
void checkSequence(const fs::path& out, const Manifest& manifest, const OutputSequence& sequence,
                   std::vector<std::string>& problems) {
  for (int frame = 1; frame <= manifest.framesWritten; ++frame) {
    const std::string relative = sequenceFilePath(sequence, manifest.framePadding, frame);
    const std::optional<std::string> bytes = readAll(out / relative);
    if (!bytes) {
      problems.push_back(cat(relative, ": missing or unreadable"));
      continue;
    }
    if (bytes->empty()) problems.push_back(cat(relative, ": empty"));
    if (sequence.format == "cache") {
      try {
        decodeCacheFrame(*bytes, relative);
      } catch (const Error& error) {
        problems.push_back(error.what());
      }
    }
  }
  // Every file of the sequence's shape in its folder, counted per frame number.
  const std::string pattern = sequence.pattern;
  const std::size_t hashes = pattern.find('#');
  const fs::path folder = out / fs::path(pattern).parent_path();
  const std::string stem = fs::path(pattern.substr(0, hashes)).filename().string();
  const std::string extension = pattern.substr(pattern.rfind('#') + 1);
  std::map<long, std::vector<std::string>> byFrame;
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, error)) {
    const std::string name = entry.path().filename().string();
    if (name.find(".tmp-") != std::string::npos && name.find(stem) != std::string::npos) {
      problems.push_back(cat(entry.path().lexically_relative(out).string(),
                             ": a temporary file a writer left when it was stopped"));
      continue;
    }
    if (name.size() <= stem.size() + extension.size() || name.rfind(stem, 0) != 0 ||
        name.compare(name.size() - extension.size(), extension.size(), extension) != 0)
      continue;
    const std::string digits =
        name.substr(stem.size(), name.size() - stem.size() - extension.size());
    if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    byFrame[std::stol(digits)].push_back(name);
  }
  for (const auto& [frame, names] : byFrame) {
    if (frame < 1 || frame > manifest.framesWritten)
      problems.push_back(cat(sequence.format, ": frame ", frame, " (", names.front(),
                             ") is outside the run's frames 1 to ", manifest.framesWritten));
    if (names.size() > 1)
      problems.push_back(cat(sequence.format, ": frame ", frame, " is there ", names.size(),
                             " times (", names[0], ", ", names[1], ")"));
  }
}

}  // namespace

int verifyCommand(const VerifyOptions& options) {
  return reportingErrors([&] {
    const Manifest manifest = readManifest(options.out);
    std::vector<std::string> problems;
    if (manifest.status != RunStatus::Complete)
      problems.push_back(cat("manifest.json: the run is ", runStatusName(manifest.status),
                             manifest.reason.empty() ? "" : cat(": ", manifest.reason)));
    for (const OutputSequence& sequence : manifest.sequences)
      checkSequence(options.out, manifest, sequence, problems);
    if (problems.empty()) {
      std::printf("%s: whole: %zu sequences of %d frames\n", options.out.string().c_str(),
                  manifest.sequences.size(), manifest.framesWritten);
      return 0;
    }
    std::fprintf(stderr, "%s: %zu problems\n", options.out.string().c_str(), problems.size());
    for (const std::string& problem : problems) std::fprintf(stderr, "  %s\n", problem.c_str());
    return 1;
  });
}

}  // namespace softbake
