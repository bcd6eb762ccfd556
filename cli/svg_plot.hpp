#pragma once
/// Line charts as inline SVG for the HTML report: no script and no network, so the report opens
/// from a file anywhere.

#include <string>

#include "cli/comparison.hpp"

namespace softbake {

/// `plot` as an <svg> element: one coloured line per series over the frames, the y axis from the
/// data (zero included) with a few round ticks, a legend.
std::string svgLineChart(const Plot& plot);

}  // namespace softbake
