#include "cli/reference_update.hpp"

#include "core/error.hpp"
#include "core/text.hpp"
#include "importers/ply_data.hpp"
#include "output/atomic_file.hpp"

namespace softbake {

namespace fs = std::filesystem;

std::vector<std::string> acceptNewFrames(const fs::path& reference,
                                         const std::vector<FramePair>& frames) {
  std::error_code error;
  const fs::path folder = fs::is_directory(reference, error) ? reference : reference.parent_path();
  std::vector<std::string> changes;
  for (const FramePair& frame : frames) {
    if (frame.verdict == Verdict::Pass) continue;
    if (!frame.candidate) {
      fs::remove(*frame.reference);
      changes.push_back(cat("removed ", frame.reference->string(), " (no new frame)"));
      continue;
    }
    const fs::path target =
        folder / ((frame.reference ? frame.reference->stem() : frame.candidate->stem()).string() +
                  frame.candidate->extension().string());
    writeFileAtomically(target, readWholeFile(frame.candidate->string()), Durability::PowerLoss);
    changes.push_back(cat(frame.reference ? "updated " : "added ", target.string()));
    if (frame.reference && *frame.reference != target) {
      fs::remove(*frame.reference);
      changes.push_back(
          cat("removed ", frame.reference->string(), " (now ", target.filename().string(), ")"));
    }
  }
  return changes;
}

}  // namespace softbake
