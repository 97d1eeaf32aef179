// Small SVG chart writers for the verify report (no plotting library is
// available offline): a scatter plot with axes, ticks, labels and a legend,
// and a top-down map of cell footprints coloured by a value. Pure code: they
// return SVG text and touch no files.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace cellbake {

struct PlotPoint {
  double x = 0, y = 0;
  std::string label;  // tooltip (<title>), may be empty
};

struct PlotSeries {
  std::string name;             // legend entry
  std::string color = "#1f77b4";  // any SVG colour
  std::vector<PlotPoint> points;
};

struct ScatterPlot {
  std::string title, x_label, y_label;
  bool log_x = false;  // logarithmic x axis (points with x <= 0 are then skipped)
  int width = 640, height = 420;  // pixels
  std::vector<PlotSeries> series;
};

// Escapes &, <, > and " for XML/HTML text and attribute values.
std::string escape_xml(const std::string& s);

// "Nice" tick values (steps of 1, 2 or 5 times a power of ten) covering
// [lo, hi] with about `target` ticks, ascending, every tick inside [lo, hi].
// lo == hi gives that one value; non-finite input or lo > hi gives {}.
std::vector<double> nice_ticks(double lo, double hi, int target = 6);

// Formats a tick value compactly ("0.25", "1.5k", "2M", "1e-05"). Deterministic.
std::string format_tick(double v);

// The plot as a complete SVG document: one <circle> per drawn point (points
// with a non-finite coordinate are skipped), axes with ticks and labels, the
// title, and a legend (drawn with <rect> swatches) when there are 2+ series.
// An empty plot still has axes and says "no data". Deterministic.
std::string scatter_plot_svg(const ScatterPlot& plot);

// Number of points scatter_plot_svg would draw (finite, and x > 0 on a log axis).
std::size_t drawable_points(const ScatterPlot& plot);

// A scatter plot from CSV text (header line of column names, then one row per
// point, comma-separated, no quoting): x and y from the named columns, one
// series per distinct value of `series_column` (all in one series when it is
// empty), tooltips from `label_column` (may be empty). Cells that do not parse
// as numbers give non-finite coordinates (not drawn). Throws
// std::invalid_argument naming a column that is missing.
ScatterPlot scatter_plot_from_csv(const std::string& csv, const std::string& x_column, const std::string& y_column,
                                  const std::string& series_column = "", const std::string& label_column = "");

struct CellMapEntry {
  std::int64_t id = 0;
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // footprint in plan (model units), x1 > x0, y1 > y0
  // NaN: drawn grey ("no data"); the best infinity (+inf when higher is
  // better: an impostor equal to the truth, PSNR = inf) is "perfect", drawn
  // in the best colour; the other infinity counts as the worst value.
  double value = 0;
};

// The cell map's id labels: this font size in pixels (at least 10 px high in
// a browser showing the SVG at 1:1, as report.html does at 1400 px wide), and
// the widest the map grows to fit them.
inline constexpr double kCellLabelFontPx = 12;
inline constexpr int kCellMapMaxWidth = 1300;

struct CellMap {
  std::string title, value_label;
  bool higher_is_better = true;  // colour ramp: the worst end is red
  int width = 720;  // pixels, at least; wider (up to kCellMapMaxWidth) when the smallest cell needs it for its
                    // label; the height follows the footprint's aspect
  std::vector<CellMapEntry> cells;
  // An absolute colour scale: values at or past `scale_worst` are red, at or
  // past `scale_best` green, linear in between (so a uniformly mediocre bake
  // looks mediocre). NaN (the default) scales to the values' own range.
  double scale_worst = std::numeric_limits<double>::quiet_NaN();
  double scale_best = std::numeric_limits<double>::quiet_NaN();
  std::string scale_unit;  // appended to the legend's numbers, e.g. " dB"
};

// A top-down map: one <rect> per cell (class "cell"), coloured from green
// (best value) through yellow to red (worst value), on the map's absolute
// scale when it has one, labelled with its id (class "cell-label", at
// kCellLabelFontPx; cells too small for it even at kCellMapMaxWidth go
// unlabelled and the subtitle says how many), a <title> tooltip naming the
// cell and its value ("perfect" for the best infinity, "no data" for NaN), the
// worst cell outlined in black and named in the subtitle, plus a colour-bar
// legend (the scale's thresholds, or the value range) with "perfect" and
// "no data" swatches. Cells are drawn in the given order (later ones on
// top where footprints overlap). Deterministic.
std::string cell_map_svg(const CellMap& map);

// The colour ramp of cell_map_svg: t = 0 (best) green, 0.5 yellow, 1 (worst)
// red, as "#rrggbb"; t is clamped to [0, 1].
std::string ramp_color(double t);

}  // namespace cellbake
