#include "runner/verify/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <limits>
#include <sstream>
#include <tuple>

namespace cellbake {
namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

// Pixels a cell id's label needs across at kCellLabelFontPx (digits ~0.6 em wide, 2 px each side).
double cell_label_width(std::int64_t id) {
  return 0.62 * kCellLabelFontPx * double(std::to_string(id).size()) + 4;
}

bool drawable(const PlotPoint& p, bool log_x) {
  return std::isfinite(p.x) && std::isfinite(p.y) && (!log_x || p.x > 0);
}

// [lo, hi] widened a little (or to a unit range when degenerate).
std::pair<double, double> padded(double lo, double hi) {
  if (!(hi > lo)) {
    const double pad = lo == 0 ? 1 : std::abs(lo) * 0.1;
    return {lo - pad, hi + pad};
  }
  const double pad = 0.05 * (hi - lo);
  return {lo - pad, hi + pad};
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int target) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) return {};
  if (lo == hi) return {lo};
  const double raw = (hi - lo) / std::max(1, target);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  std::vector<double> ticks;
  for (double k = std::ceil(lo / step - 1e-9); k * step <= hi + step * 1e-9; k += 1) {
    double t = k * step;
    if (std::abs(t) < step * 1e-9) t = 0;
    ticks.push_back(std::clamp(t, lo, hi));
  }
  return ticks;
}

std::string format_tick(double v) {
  char buf[32];
  const double a = std::abs(v);
  if (v == 0) return "0";
  if (a >= 1e6 && a < 1e12) std::snprintf(buf, sizeof buf, "%gM", v / 1e6);
  else if (a >= 1e4 && a < 1e6) std::snprintf(buf, sizeof buf, "%gk", v / 1e3);
  else std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

std::size_t drawable_points(const ScatterPlot& plot) {
  std::size_t n = 0;
  for (const auto& s : plot.series)
    for (const auto& p : s.points) n += drawable(p, plot.log_x);
  return n;
}

std::string scatter_plot_svg(const ScatterPlot& plot) {
  const double W = plot.width, H = plot.height;
  const double left = 70, right = 20, top = 40, bottom = 55;
  const double pw = W - left - right, ph = H - top - bottom;
  auto xt = [&](double x) { return plot.log_x ? std::log10(x) : x; };

  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo, y_lo = x_lo, y_hi = -x_lo;
  for (const auto& s : plot.series)
    for (const auto& p : s.points)
      if (drawable(p, plot.log_x)) {
        x_lo = std::min(x_lo, xt(p.x));
        x_hi = std::max(x_hi, xt(p.x));
        y_lo = std::min(y_lo, p.y);
        y_hi = std::max(y_hi, p.y);
      }
  const bool empty = !(x_lo <= x_hi);
  if (empty) x_lo = 0, x_hi = 1, y_lo = 0, y_hi = 1;
  std::tie(x_lo, x_hi) = padded(x_lo, x_hi);
  std::tie(y_lo, y_hi) = padded(y_lo, y_hi);
  auto px = [&](double x) { return left + (xt(x) - x_lo) / (x_hi - x_lo) * pw; };
  auto py = [&](double y) { return top + (1 - (y - y_lo) / (y_hi - y_lo)) * ph; };

  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << plot.width << "\" height=\"" << plot.height
    << "\" viewBox=\"0 0 " << plot.width << " " << plot.height << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  o << "<rect x=\"0\" y=\"0\" width=\"" << plot.width << "\" height=\"" << plot.height << "\" fill=\"white\"/>\n";
  o << "<text x=\"" << num(W / 2) << "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\" font-weight=\"bold\">"
    << escape_xml(plot.title) << "</text>\n";
  // Ticks and grid lines.
  std::vector<double> x_ticks;
  if (plot.log_x) {
    for (double e = std::ceil(x_lo); e <= std::floor(x_hi); e += 1) x_ticks.push_back(e);
    if (x_ticks.size() < 2) x_ticks = nice_ticks(x_lo, x_hi);  // less than a decade: ticks in log units
  } else {
    x_ticks = nice_ticks(x_lo, x_hi);
  }
  for (double t : x_ticks) {
    const double value = plot.log_x ? std::pow(10.0, t) : t;
    const double x = left + (t - x_lo) / (x_hi - x_lo) * pw;
    o << "<line x1=\"" << num(x) << "\" y1=\"" << num(top) << "\" x2=\"" << num(x) << "\" y2=\"" << num(top + ph)
      << "\" stroke=\"#e0e0e0\"/>\n";
    o << "<line x1=\"" << num(x) << "\" y1=\"" << num(top + ph) << "\" x2=\"" << num(x) << "\" y2=\""
      << num(top + ph + 5) << "\" stroke=\"black\"/>\n";
    o << "<text x=\"" << num(x) << "\" y=\"" << num(top + ph + 18) << "\" text-anchor=\"middle\">"
      << escape_xml(format_tick(value)) << "</text>\n";
  }
  for (double t : nice_ticks(y_lo, y_hi)) {
    const double y = py(t);
    o << "<line x1=\"" << num(left) << "\" y1=\"" << num(y) << "\" x2=\"" << num(left + pw) << "\" y2=\"" << num(y)
      << "\" stroke=\"#e0e0e0\"/>\n";
    o << "<line x1=\"" << num(left - 5) << "\" y1=\"" << num(y) << "\" x2=\"" << num(left) << "\" y2=\"" << num(y)
      << "\" stroke=\"black\"/>\n";
    o << "<text x=\"" << num(left - 8) << "\" y=\"" << num(y + 4) << "\" text-anchor=\"end\">"
      << escape_xml(format_tick(t)) << "</text>\n";
  }
  // Axes and labels.
  o << "<line x1=\"" << num(left) << "\" y1=\"" << num(top + ph) << "\" x2=\"" << num(left + pw) << "\" y2=\""
    << num(top + ph) << "\" stroke=\"black\"/>\n";
  o << "<line x1=\"" << num(left) << "\" y1=\"" << num(top) << "\" x2=\"" << num(left) << "\" y2=\"" << num(top + ph)
    << "\" stroke=\"black\"/>\n";
  o << "<text x=\"" << num(left + pw / 2) << "\" y=\"" << num(H - 12) << "\" text-anchor=\"middle\">"
    << escape_xml(plot.x_label + (plot.log_x ? " (log scale)" : "")) << "</text>\n";
  o << "<text x=\"16\" y=\"" << num(top + ph / 2) << "\" text-anchor=\"middle\" transform=\"rotate(-90 16 "
    << num(top + ph / 2) << ")\">" << escape_xml(plot.y_label) << "</text>\n";
  if (empty)
    o << "<text x=\"" << num(left + pw / 2) << "\" y=\"" << num(top + ph / 2)
      << "\" text-anchor=\"middle\" fill=\"#888\">no data</text>\n";
  // Points.
  for (const auto& s : plot.series)
    for (const auto& p : s.points) {
      if (!drawable(p, plot.log_x)) continue;
      o << "<circle cx=\"" << num(px(p.x)) << "\" cy=\"" << num(py(p.y)) << "\" r=\"3.5\" fill=\""
        << escape_xml(s.color) << "\" fill-opacity=\"0.75\">";
      if (!p.label.empty()) o << "<title>" << escape_xml(p.label) << "</title>";
      o << "</circle>\n";
    }
  // Legend.
  if (plot.series.size() >= 2) {
    double y = top + 8;
    for (const auto& s : plot.series) {
      o << "<rect x=\"" << num(left + pw - 150) << "\" y=\"" << num(y - 9) << "\" width=\"10\" height=\"10\" fill=\""
        << escape_xml(s.color) << "\"/>";
      o << "<text x=\"" << num(left + pw - 135) << "\" y=\"" << num(y) << "\">" << escape_xml(s.name) << "</text>\n";
      y += 16;
    }
  }
  o << "</svg>\n";
  return o.str();
}

ScatterPlot scatter_plot_from_csv(const std::string& csv, const std::string& x_column, const std::string& y_column,
                                  const std::string& series_column, const std::string& label_column) {
  auto split = [](const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.push_back("");
    return cells;
  };
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const std::vector<std::string> header = split(line);
  auto column = [&](const std::string& name) -> int {
    if (name.empty()) return -1;
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return int(i);
    throw std::invalid_argument("csv plot: no column \"" + name + "\"");
  };
  const int xc = column(x_column), yc = column(y_column), sc = column(series_column), lc = column(label_column);
  const char* palette[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"};
  ScatterPlot plot;
  plot.x_label = x_column;
  plot.y_label = y_column;
  auto number = [](const std::vector<std::string>& cells, int c) {
    if (c < 0 || c >= int(cells.size())) return std::numeric_limits<double>::quiet_NaN();
    char* end = nullptr;
    const double v = std::strtod(cells[c].c_str(), &end);
    return end != cells[c].c_str() && *end == 0 ? v : std::numeric_limits<double>::quiet_NaN();
  };
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const auto cells = split(line);
    const std::string series = sc >= 0 && sc < int(cells.size()) ? cells[sc] : "";
    auto it = std::find_if(plot.series.begin(), plot.series.end(), [&](const PlotSeries& s) { return s.name == series; });
    if (it == plot.series.end()) {
      plot.series.push_back({series, palette[plot.series.size() % 8], {}});
      it = plot.series.end() - 1;
    }
    it->points.push_back({number(cells, xc), number(cells, yc), lc >= 0 && lc < int(cells.size()) ? cells[lc] : ""});
  }
  return plot;
}

std::string ramp_color(double t) {
  t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0;
  // green (40, 167, 69) -> yellow (255, 193, 7) -> red (220, 38, 38)
  const double a[3] = {40, 167, 69}, b[3] = {255, 193, 7}, c[3] = {220, 38, 38};
  double rgb[3];
  for (int k = 0; k < 3; ++k) rgb[k] = t < 0.5 ? a[k] + (b[k] - a[k]) * (t / 0.5) : b[k] + (c[k] - b[k]) * ((t - 0.5) / 0.5);
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", int(std::lround(rgb[0])), int(std::lround(rgb[1])),
                int(std::lround(rgb[2])));
  return buf;
}

std::string cell_map_svg(const CellMap& map) {
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  double v_lo = x0, v_hi = -x0;
  const double perfect = map.higher_is_better ? std::numeric_limits<double>::infinity()
                                              : -std::numeric_limits<double>::infinity();
  const CellMapEntry* worst = nullptr;
  for (const auto& c : map.cells) {
    x0 = std::min(x0, c.x0), x1 = std::max(x1, c.x1), y0 = std::min(y0, c.y0), y1 = std::max(y1, c.y1);
    if (std::isnan(c.value) || c.value == perfect) continue;
    if (std::isfinite(c.value)) v_lo = std::min(v_lo, c.value), v_hi = std::max(v_hi, c.value);
    if (!worst || (map.higher_is_better ? c.value < worst->value : c.value > worst->value)) worst = &c;
  }
  if (!(x1 > x0) || !(y1 > y0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  const bool absolute = std::isfinite(map.scale_worst) && std::isfinite(map.scale_best) &&
                        map.scale_worst != map.scale_best;
  const double margin = 20, top = 56, legend_h = 60;
  // Labels at kCellLabelFontPx (readable in a browser at 1:1): the map grows
  // (up to kCellMapMaxWidth) until the smallest cell holds its label.
  double needed_scale = 0;
  for (const auto& c : map.cells)
    if (c.x1 > c.x0 && c.y1 > c.y0)
      needed_scale = std::max({needed_scale, cell_label_width(c.id) / (c.x1 - c.x0),
                               (kCellLabelFontPx + 2) / (c.y1 - c.y0)});
  const int width = int(std::clamp(std::ceil(needed_scale * (x1 - x0) + 2 * margin), double(map.width),
                                   double(std::max(map.width, kCellMapMaxWidth))));
  const double plan_w = width - 2 * margin;
  const double scale = plan_w / (x1 - x0);
  const double plan_h = (y1 - y0) * scale;
  const double height = top + plan_h + legend_h;
  // Plan y grows upwards, SVG y downwards.
  auto sx = [&](double x) { return margin + (x - x0) * scale; };
  auto sy = [&](double y) { return top + (y1 - y) * scale; };
  // 0 = best, 1 = worst.
  auto t_of = [&](double v) {
    if (v == perfect) return 0.0;
    if (!std::isfinite(v)) return 1.0;
    if (absolute) return std::clamp((v - map.scale_best) / (map.scale_worst - map.scale_best), 0.0, 1.0);
    if (!(v_hi > v_lo)) return 0.0;
    const double t = (v - v_lo) / (v_hi - v_lo);
    return map.higher_is_better ? 1 - t : t;
  };
  const std::string perfect_fill = "#1a7f3c", no_data_fill = "#bbbbbb";

  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << num(height)
    << "\" viewBox=\"0 0 " << width << " " << num(height) << "\" font-family=\"sans-serif\" font-size=\"11\">\n";
  o << "<rect x=\"0\" y=\"0\" width=\"" << width << "\" height=\"" << num(height) << "\" fill=\"white\"/>\n";
  o << "<text x=\"" << num(width / 2.0) << "\" y=\"20\" text-anchor=\"middle\" font-size=\"15\" font-weight=\"bold\">"
    << escape_xml(map.title) << "</text>\n";
  std::string subtitle = "no cell has a finite value";
  if (worst) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.4g", worst->value);
    subtitle = "worst: cell " + std::to_string(worst->id) + " (" + map.value_label + " " + buf +
               "), outlined in black; plan view";
  }
  std::size_t unlabelled = 0;
  for (const auto& c : map.cells)
    unlabelled += !((c.x1 - c.x0) * scale >= cell_label_width(c.id) && (c.y1 - c.y0) * scale >= kCellLabelFontPx + 2);
  if (unlabelled > 0)
    subtitle += "; " + std::to_string(unlabelled) + " cells too small to label: hover them for their ids";
  o << "<text x=\"" << num(width / 2.0) << "\" y=\"40\" text-anchor=\"middle\">" << escape_xml(subtitle)
    << "</text>\n";
  const double font = kCellLabelFontPx;
  for (const auto& c : map.cells) {
    std::string fill = ramp_color(t_of(c.value));
    char value_text[64];
    std::snprintf(value_text, sizeof value_text, "%.4g", c.value);
    if (std::isnan(c.value)) fill = no_data_fill, std::snprintf(value_text, sizeof value_text, "no data");
    if (c.value == perfect) fill = perfect_fill, std::snprintf(value_text, sizeof value_text, "perfect (%s)", c.value > 0 ? "inf" : "-inf");
    o << "<rect class=\"cell\" x=\"" << num(sx(c.x0)) << "\" y=\"" << num(sy(c.y1)) << "\" width=\""
      << num((c.x1 - c.x0) * scale) << "\" height=\"" << num((c.y1 - c.y0) * scale) << "\" fill=\"" << fill
      << "\" stroke=\"white\" stroke-width=\"1\"><title>cell " << c.id << ": " << escape_xml(map.value_label) << " "
      << value_text << "</title></rect>\n";
    if ((c.x1 - c.x0) * scale >= cell_label_width(c.id) && (c.y1 - c.y0) * scale >= font + 2)
      o << "<text class=\"cell-label\" x=\"" << num(sx(0.5 * (c.x0 + c.x1))) << "\" y=\""
        << num(sy(0.5 * (c.y0 + c.y1)) + font / 3) << "\" text-anchor=\"middle\" font-size=\"" << num(font)
        << "\" pointer-events=\"none\">" << c.id << "</text>\n";
  }
  if (worst)
    o << "<rect x=\"" << num(sx(worst->x0)) << "\" y=\"" << num(sy(worst->y1)) << "\" width=\""
      << num((worst->x1 - worst->x0) * scale) << "\" height=\"" << num((worst->y1 - worst->y0) * scale)
      << "\" fill=\"none\" stroke=\"black\" stroke-width=\"3\"/>\n";
  // Legend: a colour bar from worst (left) to best (right) with its end values
  // (the absolute thresholds, else the value range), then "perfect" and "no data".
  const double ly = top + plan_h + 18, lx = margin, lw = std::min(300.0, plan_w);
  for (int i = 0; i < 20; ++i)
    o << "<rect x=\"" << num(lx + lw * i / 20) << "\" y=\"" << num(ly) << "\" width=\"" << num(lw / 20 + 0.5)
      << "\" height=\"12\" fill=\"" << ramp_color(1 - i / 19.0) << "\"/>";
  o << "\n";
  const bool have_range = absolute || v_lo <= v_hi;
  const double best = absolute ? map.scale_best : map.higher_is_better ? v_hi : v_lo;
  const double worst_v = absolute ? map.scale_worst : map.higher_is_better ? v_lo : v_hi;
  const std::string worse = map.higher_is_better ? "\u2264 " : "\u2265 ", better = map.higher_is_better ? "\u2265 " : "\u2264 ";
  o << "<text x=\"" << num(lx) << "\" y=\"" << num(ly + 26) << "\">"
    << (have_range ? escape_xml((absolute ? worse : "worst ") + format_tick(worst_v) + map.scale_unit) : std::string("-"))
    << "</text>\n";
  o << "<text x=\"" << num(lx + lw) << "\" y=\"" << num(ly + 26) << "\" text-anchor=\"end\">"
    << (have_range ? escape_xml((absolute ? better : "best ") + format_tick(best) + map.scale_unit) : std::string("-"))
    << "</text>\n";
  const double sw = lx + lw + 12;
  o << "<rect x=\"" << num(sw) << "\" y=\"" << num(ly) << "\" width=\"12\" height=\"12\" fill=\"" << perfect_fill
    << "\"/><text x=\"" << num(sw + 16) << "\" y=\"" << num(ly + 10) << "\">perfect</text>\n";
  o << "<rect x=\"" << num(sw + 70) << "\" y=\"" << num(ly) << "\" width=\"12\" height=\"12\" fill=\"" << no_data_fill
    << "\"/><text x=\"" << num(sw + 86) << "\" y=\"" << num(ly + 10) << "\">no data</text>\n";
  o << "<text x=\"" << num(lx) << "\" y=\"" << num(ly + 44) << "\">" << escape_xml(map.value_label)
    << (absolute ? " (fixed scale)" : " (scaled to the values)") << "</text>\n";
  o << "</svg>\n";
  return o.str();
}

std::string escape_xml(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace cellbake
