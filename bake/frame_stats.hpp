#pragma once
/// What `run --report` records of every frame (bake/bake_report.hpp plots it): the substeps, the
/// contacts, the energy and every body's volume after the frame, and the wall time of its
/// substeps. The records live in OUT/frame_stats.jsonl, one JSON object a line, so that a run
/// continued with --resume reports the frames an earlier invocation simulated too:
///
///   {"frame":2,"substeps":4,"contacts":0,"plane_contacts":12,"step_ms":3.1,
///    "kinetic_energy":7.5,"elastic_energy":0.02,"gravity_energy":-9.8,"volumes":[0.52,0.52]}
///
/// Frame 1, the initial state, and the frame a resumed run starts from were not stepped here:
/// their substeps, contacts and step_ms are null. An open body's volume is null.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/dynamics/forces.hpp"
#include "core/simulator.hpp"

namespace softbake {

struct FrameStats {
  int frame = 0;
  /// Whether this run stepped to the frame and measured it; false for the initial state and for
  /// a frame restored from a checkpoint.
  bool stepped = false;
  int substeps = 0;
  std::size_t contacts = 0;       ///< soft and static-mesh contacts, summed over the substeps
  std::size_t planeContacts = 0;  ///< particle–plane contacts, summed over the substeps
  double stepMs = 0;              ///< wall time of the frame's substeps
  /// computeEnergy()'s terms, J: elastic is springs, gas and bulk together.
  double kineticEnergy = 0, elasticEnergy = 0, gravityEnergy = 0;
  std::vector<double> volumes;  ///< per body, in scene units³; NaN for an open body
  double totalEnergy() const { return kineticEnergy + elasticEnergy + gravityEnergy; }
};

/// The records as OUT/frame_stats.jsonl holds them, and back. Reading throws softbake::Error
/// naming `source` and the line.
std::string frameStatsText(const std::vector<FrameStats>& records);
std::vector<FrameStats> parseFrameStats(const std::string& text, const std::string& source);

/// Measures frames from a simulator and keeps their records in frame order.
class FrameStatsRecorder {
 public:
  /// Records of `topology`'s frames, saved to `file`.
  FrameStatsRecorder(const SceneTopology& topology, std::filesystem::path file);

  /// Keeps what `file` holds of frames 1 to `lastFrame` (a resumed run restores frame `lastFrame`
  /// and simulates the frames after it again). Returns a warning when the file is there but cannot
  /// be read, or an empty string; the report says which frames it lacks either way.
  std::string keepSaved(int lastFrame);

  /// The state of `simulator` now, at `frame`; `stepSeconds` the wall time of its substeps when
  /// this run stepped to it (lastFrameStats() are then the frame's).
  void record(const Simulator& simulator, int frame, std::optional<double> stepSeconds);

  bool has(int frame) const;
  /// Writes every record to the file (atomically).
  void save() const;
  const std::vector<FrameStats>& records() const { return records_; }
  const std::filesystem::path& file() const { return file_; }

 private:
  const SceneTopology& topology_;
  std::filesystem::path file_;
  ForceBuffers volumes_;  ///< scratch of computeVolumes(), sized once
  std::vector<FrameStats> records_;
};

}  // namespace softbake
