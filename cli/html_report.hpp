#pragma once
/// A comparison as one HTML page a person reads in CI's artifacts: a summary on top, plots for
/// bakes, then one row per item, failures first and worst first, with the reference, the new
/// frame (a slider and a toggle between them) and the difference. Self-contained: the style and
/// script are inline, the images lie beside it in the same folder, nothing is fetched, so it opens
/// from a file anywhere the folder is copied.

#include <filesystem>

#include "cli/comparison.hpp"

namespace softbake {

/// Writes `folder`/index.html (atomically) for `comparison`, whose items name their images
/// relative to `folder`. Throws softbake::Error naming the file.
void writeHtmlReport(const std::filesystem::path& folder, const Comparison& comparison);

}  // namespace softbake
