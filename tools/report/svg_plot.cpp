#include "tools/report/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

namespace triadcal {
namespace {

constexpr double kPanelW = 380, kPanelH = 270;         // one panel, px
constexpr double kLeft = 70, kRight = 28, kTop = 42, kBottom = 48;  // plot area margins
constexpr double kTitleH = 40;                          // figure title band

std::string Num(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%.1f", v);
  return b;
}

std::string Escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '<') o += "&lt;";
    else if (c == '>') o += "&gt;";
    else if (c == '&') o += "&amp;";
    else o += c;
  }
  return o;
}

// "0.001", "10", "1e+05": a decade label.
std::string DecadeLabel(int k) {
  char b[32];
  if (k >= -4 && k <= 4) {
    std::snprintf(b, sizeof(b), "%g", std::pow(10.0, k));
  } else {
    std::snprintf(b, sizeof(b), "1e%d", k);
  }
  return b;
}

bool Usable(double x, double y) { return std::isfinite(x) && std::isfinite(y) && x > 0 && y > 0; }

}  // namespace

std::string LogLogPanelsSvg(const std::string& title, const std::string& x_label,
                            const std::vector<PlotPanel>& panels,
                            const std::vector<std::pair<double, std::string>>& x_markers,
                            int columns) {
  columns = std::max(1, columns);
  const int rows = static_cast<int>((panels.size() + columns - 1) / columns);
  const double W = columns * kPanelW, H = kTitleH + rows * kPanelH + 30;
  // Shared x range: whole decades around every x.
  double xmin = std::numeric_limits<double>::infinity(), xmax = 0;
  for (const PlotPanel& p : panels)
    for (const PlotSeries& s : p.series)
      for (std::size_t i = 0; i < s.x.size(); ++i)
        if (Usable(s.x[i], s.y[i])) xmin = std::min(xmin, s.x[i]), xmax = std::max(xmax, s.x[i]);
  for (const auto& m : x_markers) xmin = std::min(xmin, m.first), xmax = std::max(xmax, m.first);
  if (!(xmax > 0)) xmin = 1, xmax = 10;
  const int xk0 = static_cast<int>(std::floor(std::log10(xmin)));
  const int xk1 = std::max(xk0 + 1, static_cast<int>(std::ceil(std::log10(xmax))));

  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << W << "\" height=\"" << H
    << "\" viewBox=\"0 0 " << W << " " << H << "\" font-family=\"sans-serif\" font-size=\"11\">\n";
  o << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  o << "<text x=\"" << W / 2 << "\" y=\"24\" text-anchor=\"middle\" font-size=\"15\">"
    << Escape(title) << "</text>\n";

  for (std::size_t pi = 0; pi < panels.size(); ++pi) {
    const PlotPanel& p = panels[pi];
    const double ox = (pi % columns) * kPanelW, oy = kTitleH + (pi / columns) * kPanelH;
    const double x0 = ox + kLeft, x1 = ox + kPanelW - kRight;
    const double y0 = oy + kTop, y1 = oy + kPanelH - kBottom;  // y0 top, y1 bottom
    double ymin = std::numeric_limits<double>::infinity(), ymax = 0;
    for (const PlotSeries& s : p.series)
      for (std::size_t i = 0; i < s.x.size(); ++i)
        if (Usable(s.x[i], s.y[i])) ymin = std::min(ymin, s.y[i]), ymax = std::max(ymax, s.y[i]);
    if (!(ymax > 0)) ymin = 1, ymax = 10;
    const int yk0 = static_cast<int>(std::floor(std::log10(ymin)));
    const int yk1 = std::max(yk0 + 1, static_cast<int>(std::ceil(std::log10(ymax))));
    auto X = [&](double x) { return x0 + (std::log10(x) - xk0) / (xk1 - xk0) * (x1 - x0); };
    auto Y = [&](double y) { return y1 - (std::log10(y) - yk0) / (yk1 - yk0) * (y1 - y0); };

    o << "<g>\n<text x=\"" << Num((x0 + x1) / 2) << "\" y=\"" << Num(oy + 16)
      << "\" text-anchor=\"middle\" font-size=\"12\" font-weight=\"bold\">" << Escape(p.title)
      << "</text>\n";
    if (!p.note.empty()) {
      o << "<text x=\"" << Num((x0 + x1) / 2) << "\" y=\"" << Num(oy + 31)
        << "\" text-anchor=\"middle\" fill=\"#555\">" << Escape(p.note) << "</text>\n";
    }
    // Grid: decades (solid) and 2..9 (faint).
    for (int k = xk0; k <= xk1; ++k) {
      for (int m = 1; m <= 9 && (k < xk1 || m == 1); ++m) {
        const double gx = X(m * std::pow(10.0, k));
        o << "<line x1=\"" << Num(gx) << "\" y1=\"" << Num(y0) << "\" x2=\"" << Num(gx)
          << "\" y2=\"" << Num(y1) << "\" stroke=\"" << (m == 1 ? "#ccc" : "#eee") << "\"/>\n";
      }
      o << "<text x=\"" << Num(X(std::pow(10.0, k))) << "\" y=\"" << Num(y1 + 14)
        << "\" text-anchor=\"middle\">" << DecadeLabel(k) << "</text>\n";
    }
    for (int k = yk0; k <= yk1; ++k) {
      for (int m = 1; m <= 9 && (k < yk1 || m == 1); ++m) {
        const double gy = Y(m * std::pow(10.0, k));
        o << "<line x1=\"" << Num(x0) << "\" y1=\"" << Num(gy) << "\" x2=\"" << Num(x1)
          << "\" y2=\"" << Num(gy) << "\" stroke=\"" << (m == 1 ? "#ccc" : "#eee") << "\"/>\n";
      }
      o << "<text x=\"" << Num(x0 - 4) << "\" y=\"" << Num(Y(std::pow(10.0, k)) + 4)
        << "\" text-anchor=\"end\">" << DecadeLabel(k) << "</text>\n";
    }
    o << "<rect x=\"" << Num(x0) << "\" y=\"" << Num(y0) << "\" width=\"" << Num(x1 - x0)
      << "\" height=\"" << Num(y1 - y0) << "\" fill=\"none\" stroke=\"black\"/>\n";
    o << "<text x=\"" << Num((x0 + x1) / 2) << "\" y=\"" << Num(y1 + 30)
      << "\" text-anchor=\"middle\">" << Escape(x_label) << "</text>\n";
    o << "<text transform=\"translate(" << Num(ox + 16) << "," << Num((y0 + y1) / 2)
      << ") rotate(-90)\" text-anchor=\"middle\">" << Escape(p.y_label) << "</text>\n";
    for (std::size_t mi = 0; mi < x_markers.size(); ++mi) {
      const auto& [mx, label] = x_markers[mi];
      const bool right_half = X(mx) > 0.5 * (x0 + x1);
      o << "<line x1=\"" << Num(X(mx)) << "\" y1=\"" << Num(y0) << "\" x2=\"" << Num(X(mx))
        << "\" y2=\"" << Num(y1) << "\" stroke=\"#888\" stroke-dasharray=\"2,3\"/>\n";
      o << "<text x=\"" << Num(X(mx) + (right_half ? -3 : 3)) << "\" y=\"" << Num(y0 + 11 + 12.0 * mi)
        << "\" fill=\"#555\" text-anchor=\"" << (right_half ? "end" : "start") << "\">"
        << Escape(label) << "</text>\n";
    }
    // Series and legend.
    int legend_rows = 0;
    for (const PlotSeries& s : p.series) legend_rows += s.in_legend ? 1 : 0;
    double ly = y1 - 8 - 14.0 * (legend_rows - 1);
    for (const PlotSeries& s : p.series) {
      std::string pts;
      int count = 0;
      for (std::size_t i = 0; i < s.x.size(); ++i) {
        if (!Usable(s.x[i], s.y[i])) continue;
        pts += Num(X(s.x[i])) + "," + Num(Y(s.y[i])) + " ";
        ++count;
        o << "<circle cx=\"" << Num(X(s.x[i])) << "\" cy=\"" << Num(Y(s.y[i])) << "\" r=\""
          << Num(1.2 + 0.7 * s.width) << "\" fill=\"" << s.color << "\" fill-opacity=\""
          << s.opacity << "\"/>\n";
      }
      const std::string stroke = "stroke=\"" + s.color + "\" stroke-width=\"" + Num(s.width) +
                                 "\" stroke-opacity=\"" + Num(s.opacity) + "\"" +
                                 (s.dashed ? " stroke-dasharray=\"6,3\"" : "");
      if (count > 1) {
        o << "<polyline points=\"" << pts << "\" fill=\"none\" " << stroke << "/>\n";
      }
      if (!s.in_legend) continue;
      o << "<line x1=\"" << Num(x0 + 8) << "\" y1=\"" << Num(ly - 4) << "\" x2=\"" << Num(x0 + 30)
        << "\" y2=\"" << Num(ly - 4) << "\" " << stroke << "/>\n";
      o << "<text x=\"" << Num(x0 + 34) << "\" y=\"" << Num(ly) << "\">" << Escape(s.label)
        << "</text>\n";
      ly += 14;
    }
    o << "</g>\n";
  }
  o << "</svg>\n";
  return o.str();
}

}  // namespace triadcal
