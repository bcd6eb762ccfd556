#include "bake/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "bake/markup.hpp"
#include "core/text.hpp"

namespace softbake {

namespace {

constexpr const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e",
                                   "#9467bd", "#8c564b", "#e377c2", "#17becf"};

/// A round step for about `count` ticks over `range`: 1, 2 or 5 times a power of ten.
double tickStep(double range, int count) {
  const double raw = range / count, power = std::pow(10, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0})
    if (m * power >= raw) return m * power;
  return 10 * power;
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

}  // namespace

std::string svgLineChart(const Plot& plot) {
  constexpr double width = 720, height = 240, left = 64, right = 150, top = 28, bottom = 30;
  const double plotWidth = width - left - right, plotHeight = height - top - bottom;
  double low = 0, high = 0;
  for (const std::vector<double>& values : plot.series)
    for (const double v : values)
      if (std::isfinite(v)) low = std::min(low, v), high = std::max(high, v);
  for (const double v : plot.guides)
    if (std::isfinite(v)) low = std::min(low, v), high = std::max(high, v);
  if (high - low <= 0) high = low + 1;
  const double step = tickStep(high - low, 4);
  low = std::floor(low / step) * step;
  high = std::ceil(high / step) * step;
  const int first = plot.frames.empty() ? 1 : plot.frames.front();
  int last = plot.frames.empty() ? 1 : plot.frames.back();
  for (const int frame : plot.marks) last = std::max(last, frame);
  last = std::max(last, first + 1);
  const auto x = [&](double frame) {
    return left + plotWidth * (frame - first) / double(last - first);
  };
  const auto y = [&](double v) { return top + plotHeight * (high - v) / (high - low); };

  std::string svg = cat("<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" width=\"", width,
                        "\" height=\"", height, "\" viewBox=\"0 0 ", width, " ", height,
                        "\" font-family=\"sans-serif\" font-size=\"11\">\n<text x=\"", left,
                        "\" y=\"16\" "
                        "font-size=\"13\" font-weight=\"bold\">",
                        escapeMarkup(plot.title), " (", escapeMarkup(plot.unit), ")</text>\n");
  for (double v = low; v <= high + step / 2; v += step)
    svg += cat("<line x1=\"", left, "\" x2=\"", left + plotWidth, "\" y1=\"", y(v), "\" y2=\"",
               y(v), "\" stroke=\"#ddd\"/><text x=\"", left - 6, "\" y=\"", y(v) + 4,
               "\" text-anchor=\"end\">", number(std::abs(v) < step / 1e6 ? 0 : v), "</text>\n");
  // Half a frame each side, so that a single marked frame stays visible on a long run.
  const double halfFrame = std::max(0.5, (last - first) / plotWidth);
  for (const int frame : plot.marks) {
    const double from = x(std::max<double>(first, frame - halfFrame)),
                 to = x(std::min<double>(last, frame + halfFrame));
    svg += cat("<rect class=\"mark\" x=\"", number(from), "\" y=\"", top, "\" width=\"",
               number(to - from), "\" height=\"", plotHeight, "\" fill=\"#f4a0a0\"/>\n");
  }
  for (const double v : plot.guides)
    if (std::isfinite(v))
      svg += cat("<line class=\"guide\" x1=\"", left, "\" x2=\"", left + plotWidth, "\" y1=\"",
                 number(y(v)), "\" y2=\"", number(y(v)),
                 "\" stroke=\"#b00\" stroke-dasharray=\"4 3\"/>\n");
  const double frameStep = std::max(1.0, tickStep(last - first, 6));
  for (double f = first; f <= last; f += frameStep)
    svg += cat("<text x=\"", x(int(f)), "\" y=\"", top + plotHeight + 16,
               "\" text-anchor=\"middle\">", int(f), "</text>\n");
  svg += cat("<text x=\"", left + plotWidth / 2, "\" y=\"", height - 1,
             "\" text-anchor=\"middle\">frame</text>\n");
  for (std::size_t s = 0; s < plot.series.size(); ++s) {
    const char* color = kColors[s % std::size(kColors)];
    std::string points;
    const auto flush = [&] {
      if (!points.empty())
        svg += cat("<polyline fill=\"none\" stroke=\"", color, "\" stroke-width=\"1.5\" points=\"",
                   points, "\"/>\n");
      points.clear();
    };
    for (std::size_t i = 0; i < plot.frames.size() && i < plot.series[s].size(); ++i) {
      const double v = plot.series[s][i];
      if (!std::isfinite(v)) {
        flush();
        continue;
      }
      points += cat(number(x(plot.frames[i])), ",", number(y(v)), " ");
    }
    flush();
    const double legendY = top + 14 * double(s) + 6;
    svg += cat("<line x1=\"", left + plotWidth + 12, "\" x2=\"", left + plotWidth + 30, "\" y1=\"",
               legendY, "\" y2=\"", legendY, "\" stroke=\"", color,
               "\" stroke-width=\"2\"/><text x=\"", left + plotWidth + 36, "\" y=\"", legendY + 4,
               "\">", escapeMarkup(s < plot.names.size() ? plot.names[s] : ""), "</text>\n");
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace softbake
