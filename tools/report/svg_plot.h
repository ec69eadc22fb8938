// A small hand-written SVG writer for log-log line plots in panels (the
// `design` command's sigma against duration). No plotting library: axes with
// decade ticks and labels, a light grid, lines with markers, a legend, and
// labelled vertical markers.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace triadcal {

struct PlotSeries {
  std::string label;
  std::string color;   // SVG colour, e.g. "#1f77b4"
  bool dashed = false;
  std::vector<double> x, y;  // points with y <= 0 or not finite are left out
  double width = 1.8;        // line width, px
  double opacity = 1.0;
  bool in_legend = true;
};

struct PlotPanel {
  std::string title;    // e.g. "scale factors K (worst axis)"
  std::string y_label;  // e.g. "sigma [mV/g]"
  std::vector<PlotSeries> series;
  std::string note;     // one line under the title, e.g. "static: not determined"
};

// Panels on a grid of `columns`, shared x axis range and label; x_markers are
// vertical dotted lines (x, label) drawn in every panel.
std::string LogLogPanelsSvg(const std::string& title, const std::string& x_label,
                            const std::vector<PlotPanel>& panels,
                            const std::vector<std::pair<double, std::string>>& x_markers,
                            int columns);

}  // namespace triadcal
