#pragma once
/// `softbake export OUT --frames A:B [--obj] [--vdb] [--png] [--contacts]`: writes frames of a
/// finished (or partly finished) run again from its simulation cache, without simulating: the
/// same bytes `run` writes for those frames, with the run's recorded options. Outputs nobody asked
/// for at run time come later this way, and a farm splits a shot's exports into frame ranges.

#include <filesystem>
#include <optional>
#include <string>

namespace softbake {

struct ExportOptions {
  std::filesystem::path out;  ///< the run's output folder, holding manifest.json and cache/
  std::string frames;         ///< "A:B", "A" or empty for every frame of the cache
  bool obj = false, vdb = false, png = false, contacts = false, pc2 = false, mdd = false;
  bool all = false;  ///< every output the run's scene and options ask for
  /// Renders the PNG frames in this contact view ("xray", "opaque") instead of the run's.
  std::optional<std::string> contactsView;
  int threads = 0;  ///< 0: all cores
  bool quiet = false;
};

/// Returns the process exit code. Errors are printed, never thrown.
int exportCommand(const ExportOptions& options);

}  // namespace softbake
