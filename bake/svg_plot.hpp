#pragma once
/// Line charts as inline SVG for the HTML reports (compare's and run's): no script and no network,
/// so the report opens from a file anywhere.

#include <string>
#include <vector>

namespace softbake {

/// A line chart over the frames: one series per name.
struct Plot {
  std::string title, unit;
  std::vector<int> frames;
  std::vector<std::string> names;
  std::vector<std::vector<double>> series;  ///< per name, a value per frame (NaN: none)
  /// Frames drawn as bands behind the lines, where something went wrong; the x axis reaches the
  /// last of them (a frame that failed has no value).
  std::vector<int> marks;
  std::vector<double> guides;  ///< values drawn as dashed lines across: thresholds
};

/// `plot` as an <svg> element: one coloured line per series over the frames, the y axis from the
/// data (zero included) with a few round ticks, a legend; the marked frames as red bands, the
/// guides as dashed lines.
std::string svgLineChart(const Plot& plot);

}  // namespace softbake
