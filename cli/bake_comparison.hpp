#pragma once
/// Two bakes compared frame by frame and body by body (`softbake compare OUT_A OUT_B`): did the
/// simulation change? The geometry answers exactly where rendered frames blur it.
///
/// Per frame and body: the largest and the RMS distance between a particle in A and the same
/// particle in B, as a fraction of the body's size (the largest side of its bounding box in A's
/// first frame); the change of its volume, as a fraction of A's; the contacts it takes part in.
/// A body whose particles or triangles differ has changed topology: a failure. Bakes whose bodies
/// differ are of different scenes: an error.

#include <filesystem>

#include "cli/comparison.hpp"

namespace softbake {

struct BakeThresholds {
  double maxDistance = 1e-3;      ///< largest particle distance, fraction of the body's size
  double maxRms = 5e-4;           ///< RMS particle distance, fraction of the body's size
  double maxVolumeChange = 1e-3;  ///< |V_B − V_A| / |V_A|
  /// |N_B − N_A| / max(N_A, 1) of a body's contacts in a frame
  double maxContactChange = 0.1;
};

/// Compares the bake in `candidate` with the one in `reference` (cli/bake_sequence.hpp says what
/// a bake folder may be). A frame one of them lacks fails, named. Throws softbake::Error when
/// either cannot be read or they are bakes of different scenes.
Comparison compareBakes(const std::filesystem::path& reference,
                        const std::filesystem::path& candidate, const BakeThresholds& thresholds);

}  // namespace softbake
