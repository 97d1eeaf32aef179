#include "runner/walk/walk_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "runner/verify/svg_plot.h"

namespace cellbake {
namespace {

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

struct Panel {
  double top, height;  // pixels
  double lo, hi;       // value range
  double y(double v) const { return top + height * (1 - (std::clamp(v, lo, hi) - lo) / (hi - lo)); }
};

std::pair<double, double> range_of(const std::vector<double>& values, double min_span) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const double v : values)
    if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  if (!(hi >= lo)) return {0, 1};
  if (hi - lo < min_span) {
    const double mid = 0.5 * (lo + hi);
    lo = mid - 0.5 * min_span, hi = mid + 0.5 * min_span;
  }
  const double pad = 0.06 * (hi - lo);
  return {lo - pad, hi + pad};
}

}  // namespace

std::string walk_plot_svg(const std::vector<WalkFrame>& frames, const std::string& title, int width) {
  const double W = std::max(width, 300), left = 70, right = 20, top = 50, gap = 50, panel_h = 170, bottom = 50;
  const double H = top + 2 * panel_h + gap + bottom, pw = W - left - right;
  const double t_end = frames.empty() ? 1 : std::max(frames.back().t, 1e-3);
  auto x = [&](double t) { return left + pw * std::clamp(t / t_end, 0.0, 1.0); };

  std::vector<double> psnr, ms;
  for (const WalkFrame& f : frames) {
    if (!f.fallback && std::isfinite(f.psnr_db)) psnr.push_back(f.psnr_db);
    ms.push_back(f.frame_ms);
    ms.push_back(f.truth_ms);
  }
  auto [p_lo, p_hi] = range_of(psnr, 2.0);
  auto [m_lo, m_hi] = range_of(ms, 1.0);
  m_lo = std::max(0.0, std::min(m_lo, 0.0));
  const Panel pp{top, panel_h, p_lo, p_hi}, mp{top + panel_h + gap, panel_h, m_lo, m_hi};

  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << num(W) << "\" height=\"" << num(H) << "\" viewBox=\"0 0 "
    << num(W) << " " << num(H) << "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  o << "<rect x=\"0\" y=\"0\" width=\"" << num(W) << "\" height=\"" << num(H) << "\" fill=\"white\"/>\n";
  o << "<text x=\"" << num(W / 2) << "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\" font-weight=\"bold\">"
    << escape_xml(title) << "</text>\n";
  const auto axes = [&](const Panel& p, const std::string& label) {
    o << "<rect x=\"" << num(left) << "\" y=\"" << num(p.top) << "\" width=\"" << num(pw) << "\" height=\""
      << num(p.height) << "\" fill=\"none\" stroke=\"#888\"/>\n";
    for (const double v : nice_ticks(p.lo, p.hi, 5))
      o << "<line x1=\"" << num(left - 4) << "\" x2=\"" << num(left + pw) << "\" y1=\"" << num(p.y(v)) << "\" y2=\""
        << num(p.y(v)) << "\" stroke=\"#eee\"/><text x=\"" << num(left - 6) << "\" y=\"" << num(p.y(v) + 4)
        << "\" text-anchor=\"end\">" << escape_xml(format_tick(v)) << "</text>\n";
    o << "<text x=\"16\" y=\"" << num(p.top + p.height / 2) << "\" text-anchor=\"middle\" transform=\"rotate(-90 16 "
      << num(p.top + p.height / 2) << ")\">" << escape_xml(label) << "</text>\n";
  };
  axes(pp, "PSNR, dB");
  axes(mp, "frame time, ms");
  for (const double t : nice_ticks(0, t_end, 10))
    o << "<text x=\"" << num(x(t)) << "\" y=\"" << num(mp.top + mp.height + 16) << "\" text-anchor=\"middle\">"
      << escape_xml(format_tick(t)) << "</text>\n";
  o << "<text x=\"" << num(left + pw / 2) << "\" y=\"" << num(H - 12)
    << "\" text-anchor=\"middle\">walk time, s (dashed: cell switches, labelled with the cell entered)</text>\n";
  if (frames.empty()) {
    o << "<text x=\"" << num(left + pw / 2) << "\" y=\"" << num(pp.top + pp.height / 2)
      << "\" text-anchor=\"middle\">no frames</text>\n</svg>\n";
    return o.str();
  }
  // Cell switches under the lines.
  for (const WalkFrame& f : frames) {
    if (!f.cell_switch) continue;
    o << "<line class=\"switch\" x1=\"" << num(x(f.t)) << "\" x2=\"" << num(x(f.t)) << "\" y1=\"" << num(pp.top)
      << "\" y2=\"" << num(mp.top + mp.height) << "\" stroke=\"#999\" stroke-dasharray=\"4 3\"><title>frame "
      << f.index << ": enters cell " << f.cell << "</title></line><text x=\"" << num(x(f.t) + 2) << "\" y=\""
      << num(pp.top - 4) << "\" font-size=\"11\" fill=\"#555\">" << f.cell << "</text>\n";
  }
  // The first cell's label at the start.
  o << "<text x=\"" << num(left + 2) << "\" y=\"" << num(pp.top - 4) << "\" font-size=\"11\" fill=\"#555\">"
    << frames.front().cell << "</text>\n";
  const auto polyline = [&](const char* cls, const char* colour, const Panel& p, auto value, auto keep) {
    std::string points;
    const auto flush = [&] {
      if (!points.empty())
        o << "<polyline class=\"" << cls << "\" fill=\"none\" stroke=\"" << colour << "\" stroke-width=\"1.5\" points=\""
          << points << "\"/>\n";
      points.clear();
    };
    for (const WalkFrame& f : frames) {
      if (!keep(f)) {
        flush();
        continue;
      }
      points += (points.empty() ? "" : " ") + num(x(f.t)) + "," + num(p.y(value(f)));
    }
    flush();
  };
  polyline("psnr", "#1f77b4", pp, [](const WalkFrame& f) { return f.psnr_db; },
           [](const WalkFrame& f) { return !f.fallback && std::isfinite(f.psnr_db); });
  for (const WalkFrame& f : frames)
    if (!f.fallback && std::isinf(f.psnr_db) && f.psnr_db > 0)
      o << "<circle cx=\"" << num(x(f.t)) << "\" cy=\"" << num(pp.top + 3) << "\" r=\"2.5\" fill=\"none\" stroke=\"#1f77b4\"/>\n";
  polyline("truth-ms", "#aaaaaa", mp, [](const WalkFrame& f) { return f.truth_ms; },
           [](const WalkFrame&) { return true; });
  polyline("frame-ms", "#d62728", mp, [](const WalkFrame& f) { return f.frame_ms; },
           [](const WalkFrame&) { return true; });
  // Legend.
  const double ly = mp.top + 14, lx = left + pw - 250;
  o << "<rect x=\"" << num(lx) << "\" y=\"" << num(ly - 10) << "\" width=\"12\" height=\"3\" fill=\"#d62728\"/><text x=\""
    << num(lx + 16) << "\" y=\"" << num(ly - 6) << "\">cells frame (load + draw)</text>\n";
  o << "<rect x=\"" << num(lx) << "\" y=\"" << num(ly + 6) << "\" width=\"12\" height=\"3\" fill=\"#aaaaaa\"/><text x=\""
    << num(lx + 16) << "\" y=\"" << num(ly + 10) << "\">truth frame</text>\n";
  o << "</svg>\n";
  return o.str();
}

}  // namespace cellbake
