#pragma once
/// `run --report DIR`: one HTML page an artist opens to see where a bake went wrong. A summary on
/// top (the run, its peaks, each body's worst volume change, where it failed), the frames that
/// look wrong, plots per frame (substeps, contacts, energy, volume per body, step time) with those
/// frames marked, and a flipbook of the PNG frames with each frame's numbers beside it.
/// Self-contained: DIR/index.html with the style, script and data inline, and the frames in
/// DIR/frames/, so the folder opens from disk anywhere it is copied.

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bake/frame_stats.hpp"

namespace softbake {

/// When a frame is flagged: a closed body's volume more than this fraction from its rest volume.
inline constexpr double kReportVolumeLimit = 0.10;
/// When a frame is flagged: the total energy (kinetic, elastic and gravity's) rose in it by more
/// than this fraction of the largest kinetic plus elastic energy up to it. Nothing in a scene adds
/// energy (the response only takes it away; springs, gas and damping keep or lose it), so a rise
/// is the integrator going unstable or a push that should not be there. Measured at frame ends,
/// the examples' largest rise is 2.9% (sheet_ball, the ball landing in the sheet); an explicit
/// run past its stability bound rises by 20–100% a frame before it blows up.
inline constexpr double kReportEnergyRise = 0.10;

struct BakeReportBody {
  std::string name;
  bool closed = false;
  double restVolume = 0;
  /// Its material resists a change of volume (a bulk modulus): only then is a change beyond
  /// kReportVolumeLimit flagged. Under the paper's gas law alone (a balloon, the figures' bodies)
  /// the volume follows the load by design: a balloon in the mixed pile stays 39% above rest.
  bool keepsVolume = true;
};

/// Everything the report shows, gathered by `run`.
struct BakeReport {
  std::string scene;  ///< the scene's name
  std::string input;  ///< as given; empty for the built-in scene
  std::filesystem::path out;
  int frames = 0;  ///< of the run
  double fps = 24;
  std::string integrator;
  std::string substeps;           ///< "auto", or the count asked for
  std::optional<int> substepCap;  ///< the substeps "auto" stops at; unset where there is none
  std::vector<BakeReportBody> bodies;
  std::vector<FrameStats> records;  ///< in frame order
  double wallSeconds = 0;           ///< of this invocation
  std::string status;               ///< "complete", "failed", "interrupted"
  std::string failure;              ///< why the run stopped early
  int failedFrame = 0;              ///< the frame that blew up; 0 when none did
  std::vector<std::string> notes;   ///< what the report lacks, and why
  /// The PNG frames the run left, by frame number, each a file that exists.
  std::vector<std::pair<int, std::filesystem::path>> pngFrames;
};

/// Writes `folder`/index.html and `folder`/frames/ (each file atomically; the frames hard-linked
/// where the file system allows, else copied; images an earlier report left there removed).
/// Throws softbake::OutputFailure naming the file.
void writeBakeReport(const std::filesystem::path& folder, const BakeReport& report);

}  // namespace softbake
