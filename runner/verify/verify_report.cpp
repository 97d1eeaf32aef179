#include "runner/verify/verify_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "runner/verify/svg_plot.h"

namespace cellbake {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

nlohmann::json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

double number_from(const nlohmann::json& j, const char* key, double if_null) {
  const auto& v = j.at(key);
  return v.is_null() ? if_null : v.get<double>();
}

nlohmann::json vec_json(const Vec3d& v) { return nlohmann::json::array({v.x, v.y, v.z}); }
Vec3d vec_from(const nlohmann::json& j) {
  return {j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>()};
}

std::string fmt(double v, const char* format = "%.4g") {
  if (std::isnan(v)) return "&ndash;";
  if (std::isinf(v)) return v > 0 ? "&infin;" : "&minus;&infin;";
  char buf[48];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

double max_of(const VerifyCellResult& c, double VerifyViewResult::*field) {
  double m = kNaN;
  for (const auto& v : c.views)
    if (!std::isnan(v.*field) && !(m >= v.*field)) m = v.*field;
  return m;
}

// "1.2 % → 0.8 % → 0.4 %" over the samples whose void was measured.
std::string void_curve_text(const VerifyCellResult& c) {
  std::string out;
  char buf[32];
  for (double v : c.void_curve) {
    if (v < 0) continue;
    std::snprintf(buf, sizeof buf, "%.2f %%", 100 * v);
    out += (out.empty() ? "" : " &rarr; ") + std::string(buf);
  }
  return out.empty() ? "&ndash;" : out;
}

// Over the cell's headline (random) views whose truth is not blank (NaN when none is).
double cell_median(const VerifyCellResult& c, double VerifyViewResult::*field) {
  std::vector<double> v;
  for (const auto& view : c.views)
    if (!view.truth_blank && is_headline_view(view.kind)) v.push_back(view.*field);
  return median_of(v);
}

void write_svg(const std::filesystem::path& file, const std::string& svg, VerifyReportFiles& files,
               const InputFiles& inputs) {
  write_text_file_atomically(file, svg, inputs);
  files.plots.push_back(file);
}

// Standard base64 (RFC 4648, with padding), for data: URIs.
std::string base64(const std::string& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v =
        (unsigned char)bytes[i] << 16 | (unsigned char)bytes[i + 1] << 8 | (unsigned char)bytes[i + 2];
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], k[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const unsigned v = (unsigned char)bytes[i] << 16;
    out += {k[v >> 18], k[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const unsigned v = (unsigned char)bytes[i] << 16 | (unsigned char)bytes[i + 1] << 8;
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], '='};
  }
  return out;
}

// The file's bytes as a data: URI ("" when it cannot be read).
std::string png_data_uri(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return "";
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return "data:image/png;base64," + base64(bytes.str());
}

// An SVG document for inlining into HTML: from its <svg element on (no XML prolog).
std::string inline_svg(const std::string& svg) {
  const auto at = svg.find("<svg");
  return at == std::string::npos ? svg : svg.substr(at);
}

const char* kind_color(VerifyViewKind k) {
  switch (k) {
    case VerifyViewKind::centre:
      return "#1f77b4";
    case VerifyViewKind::corner:
      return "#d62728";
    case VerifyViewKind::random:
      return "#2ca02c";
    case VerifyViewKind::sample:
      return "#9467bd";
  }
  return "#000";
}

// One series per view kind, points (x(view, cell), y(view)).
template <class X, class Y>
std::vector<PlotSeries> per_view_series(const std::vector<VerifyCellResult>& cells, X x, Y y) {
  std::vector<PlotSeries> series;
  for (VerifyViewKind k :
       {VerifyViewKind::random, VerifyViewKind::centre, VerifyViewKind::corner, VerifyViewKind::sample}) {
    PlotSeries s{std::string(view_kind_name(k)) + " views", kind_color(k), {}};
    for (const auto& c : cells)
      for (std::size_t i = 0; i < c.views.size(); ++i)
        if (c.views[i].kind == k)
          s.points.push_back({x(c.views[i], c), y(c.views[i]),
                              "cell " + std::to_string(c.id) + " view " + std::to_string(i)});
    if (!s.points.empty()) series.push_back(std::move(s));
  }
  return series;
}

// How many distinct eye-to-sample distances the distance plots would show
// (views with a finite distance and PSNR; distances within 1e-6 of the
// largest, or of 1, count as one; all below that count as none).
std::size_t distinct_sample_distances(const std::vector<VerifyCellResult>& cells) {
  std::vector<double> d;
  for (const auto& c : cells)
    for (const auto& v : c.views)
      if (std::isfinite(v.distance_from_sample) && std::isfinite(v.psnr_db)) d.push_back(v.distance_from_sample);
  if (d.empty()) return 0;
  std::sort(d.begin(), d.end());
  const double eps = 1e-6 * std::max(1.0, d.back());
  if (d.back() <= eps) return 0;
  std::size_t n = 1;
  for (std::size_t i = 1; i < d.size(); ++i) n += d[i] - d[i - 1] > eps;
  return n;
}

}  // namespace

double VerifyCellResult::bake_seconds_total() const {
  double s = 0;
  for (const auto& [stage, seconds] : bake_seconds) s += seconds;
  return s;
}

double median_of(const std::vector<double>& values) {
  std::vector<double> v;
  for (double x : values)
    if (!std::isnan(x)) v.push_back(x);
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  if (n % 2) return v[n / 2];
  const double a = v[n / 2 - 1], b = v[n / 2];
  return a == b ? a : 0.5 * (a + b);  // inf + inf stays inf; inf - inf is avoided
}

double psnr_difference(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::numeric_limits<double>::quiet_NaN();
  if (std::isinf(a) && std::isinf(b) && (a > 0) == (b > 0)) return 0;
  return a - b;
}

const std::vector<MetricInfo>& verify_metrics() {
  static const std::vector<MetricInfo> metrics{
      {"psnr_db", true, &VerifyViewResult::psnr_db},
      {"ssim", true, &VerifyViewResult::ssim},
      {"hole_fraction", false, &VerifyViewResult::hole_fraction},
      {"psnr_db_root", true, &VerifyViewResult::psnr_db_root},
      {"hole_fraction_root", false, &VerifyViewResult::hole_fraction_root},
      {"skin_fraction", false, &VerifyViewResult::skin_fraction},
      {"extra_fraction", false, &VerifyViewResult::extra_fraction},
      {"depth_error_median", false, &VerifyViewResult::depth_error_median},
      {"triangle_ratio", false, &VerifyViewResult::triangle_ratio},
      {"ms_impostor", false, &VerifyViewResult::ms_impostor},
      {"ms_truth", false, &VerifyViewResult::ms_truth},
      {"psnr_db_cut", true, &VerifyViewResult::psnr_db_cut},
      {"psnr_gain_over_cut", true, &VerifyViewResult::psnr_gain_over_cut},
      {"cut_error_px", false, &VerifyViewResult::cut_error_px},
      {"psnr_db_cut_1px", true, &VerifyViewResult::psnr_db_cut_1px},
      {"triangles_cut_1px", false, &VerifyViewResult::triangles_cut_1px},
  };
  return metrics;
}

MetricStats metric_stats(const std::vector<VerifyCellResult>& cells, const MetricInfo& metric) {
  MetricStats s;
  std::vector<double> random, centre, corner, sample, reference;
  for (const auto& c : cells)
    for (std::size_t i = 0; i < c.views.size(); ++i) {
      const VerifyViewResult& view = c.views[i];
      const double v = view.*metric.field;
      if (std::isnan(v) || view.truth_blank) continue;
      switch (view.kind) {
        case VerifyViewKind::random:
          random.push_back(v);
          break;
        case VerifyViewKind::centre:
          centre.push_back(v);
          break;
        case VerifyViewKind::corner:
          corner.push_back(v);
          break;
        case VerifyViewKind::sample:
          sample.push_back(v);
          break;
      }
      if (!is_headline_view(view.kind)) {
        reference.push_back(v);
        continue;
      }
      if (s.count++ == 0 || (metric.higher_is_better ? v < s.worst : v > s.worst)) {
        s.worst = v;
        s.worst_cell = c.id;
        s.worst_view = int(i);
      }
    }
  s.median = median_of(random);
  s.median_centre = median_of(centre);
  s.median_corner = median_of(corner);
  s.median_sample = median_of(sample);
  s.median_reference = median_of(reference);
  return s;
}

bool worse_view(const VerifyViewResult& a, const VerifyViewResult& b) {
  if (a.truth_blank != b.truth_blank) return b.truth_blank;
  return a.psnr_db < b.psnr_db || (a.psnr_db == b.psnr_db && a.hole_fraction > b.hole_fraction);
}

int worst_view_index(const std::vector<VerifyViewResult>& views) {
  int worst = -1;
  for (int i = 0; i < int(views.size()); ++i)
    if (is_headline_view(views[i].kind) && (worst < 0 || worse_view(views[i], views[worst]))) worst = i;
  return worst;
}

nlohmann::json to_json(const VerifyViewResult& v) {
  nlohmann::json j = {{"kind", view_kind_name(v.kind)},
          {"eye", vec_json(v.eye)},
          {"look", vec_json(v.look)},
          {"distance_from_sample", v.distance_from_sample},
          {"psnr_db", number_or_null(v.psnr_db)},
          {"ssim", number_or_null(v.ssim)},
          {"hole_fraction", number_or_null(v.hole_fraction)},
          {"skin_fraction", number_or_null(v.skin_fraction)},
          {"extra_fraction", number_or_null(v.extra_fraction)},
          {"depth_error_median", number_or_null(v.depth_error_median)},
          {"psnr_db_root", number_or_null(v.psnr_db_root)},
          {"hole_fraction_root", number_or_null(v.hole_fraction_root)},
          {"samples_drawn", v.samples_drawn},
          {"truth_blank", v.truth_blank},
          {"triangles_impostor", v.triangles_impostor},
          {"triangles_truth", v.triangles_truth},
          {"triangle_ratio", number_or_null(v.triangle_ratio)},
          {"ms_impostor", number_or_null(v.ms_impostor)},
          {"ms_truth", number_or_null(v.ms_truth)},
          {"psnr_db_cut", number_or_null(v.psnr_db_cut)},
          {"cut_error_px", number_or_null(v.cut_error_px)},
          {"psnr_db_cut_1px", number_or_null(v.psnr_db_cut_1px)},
          {"triangles_cut_1px", number_or_null(v.triangles_cut_1px)},
          {"far_budget_sweep", [&] {
             nlohmann::json points = nlohmann::json::array();
             for (const FarBudgetPoint& p : v.far_budget_sweep)
               points.push_back(
                   {{"far_budget", p.far_budget}, {"triangles", p.triangles}, {"psnr_db", number_or_null(p.psnr_db)}});
             return points;
           }()}};
  // The cut's figures only where it was measured (--lod-cut): a null PSNR
  // reads back as +infinity, which would count an unmeasured cut as identical.
  if (std::isnan(v.psnr_db_cut))
    for (const char* key : {"psnr_db_cut", "cut_error_px", "psnr_db_cut_1px", "triangles_cut_1px"}) j.erase(key);
  return j;
}

nlohmann::json to_json(const VerifyCellResult& c) {
  nlohmann::json views = nlohmann::json::array();
  for (const auto& v : c.views) views.push_back(to_json(v));
  nlohmann::json j{{"id", c.id},
                   {"bounds", {vec_json(c.bounds.lo), vec_json(c.bounds.hi)}},
                   {"key", c.key},
                   {"bake_seconds", c.bake_seconds},
                   {"bake_seconds_total", c.bake_seconds_total()},
                   {"bytes", c.bytes},
                   {"colour_bytes", c.colour_bytes},
                   {"mesh_bytes", c.mesh_bytes},
                   {"near_list_bytes", c.near_list_bytes},
                   {"near_triangles", c.near_triangles},
                   {"far_triangles", c.far_triangles},
                   {"far_geometry_triangles", c.far_geometry_triangles},
                   {"void_curve", c.void_curve},
                   {"sample_seconds", c.sample_seconds},
                   {"views", views},
                   {"triptych", c.triptych},
                   {"worst_view", c.worst_view}};
  if (!c.error.empty()) j["error"] = c.error;
  return j;
}

VerifyCellResult cell_from_json(const nlohmann::json& j) {
  VerifyCellResult c;
  c.id = j.at("id").get<std::int64_t>();
  c.bounds = {vec_from(j.at("bounds").at(0)), vec_from(j.at("bounds").at(1))};
  c.key = j.at("key").get<std::string>();
  c.bake_seconds = j.at("bake_seconds").get<std::map<std::string, double>>();
  c.bytes = j.at("bytes").get<std::uint64_t>();
  c.colour_bytes = j.value("colour_bytes", std::uint64_t{0});
  c.mesh_bytes = j.value("mesh_bytes", std::uint64_t{0});
  c.near_list_bytes = j.value("near_list_bytes", std::uint64_t{0});
  c.near_triangles = j.at("near_triangles").get<std::uint64_t>();
  c.far_triangles = j.at("far_triangles").get<std::uint64_t>();
  c.far_geometry_triangles = j.value("far_geometry_triangles", std::uint64_t{0});
  c.void_curve = j.value("void_curve", std::vector<double>{});
  c.sample_seconds = j.value("sample_seconds", std::vector<double>{});
  c.triptych = j.at("triptych").get<std::string>();
  c.worst_view = j.at("worst_view").get<int>();
  c.error = j.value("error", std::string());
  for (const auto& v : j.at("views")) {
    VerifyViewResult r;
    r.kind = parse_view_kind(v.at("kind").get<std::string>());
    r.eye = vec_from(v.at("eye"));
    r.look = vec_from(v.at("look"));
    r.distance_from_sample = v.at("distance_from_sample").get<double>();
    r.psnr_db = number_from(v, "psnr_db", std::numeric_limits<double>::infinity());
    r.ssim = number_from(v, "ssim", kNaN);
    r.hole_fraction = number_from(v, "hole_fraction", kNaN);
    r.skin_fraction = number_from(v, "skin_fraction", kNaN);
    r.extra_fraction = number_from(v, "extra_fraction", kNaN);
    if (v.contains("far_budget_sweep"))
      for (const auto& p : v.at("far_budget_sweep"))
        r.far_budget_sweep.push_back({p.at("far_budget").get<std::uint64_t>(), p.at("triangles").get<std::uint64_t>(),
                                      number_from(p, "psnr_db", std::numeric_limits<double>::infinity())});
    r.depth_error_median = number_from(v, "depth_error_median", kNaN);
    // Absent in reports of older versions.
    r.psnr_db_root = v.contains("psnr_db_root")
                         ? number_from(v, "psnr_db_root", std::numeric_limits<double>::infinity())
                         : kNaN;
    r.hole_fraction_root =
        v.contains("hole_fraction_root") ? number_from(v, "hole_fraction_root", kNaN) : kNaN;
    r.samples_drawn = v.value("samples_drawn", std::uint64_t{0});
    r.truth_blank = v.value("truth_blank", false);
    r.triangles_impostor = v.at("triangles_impostor").get<std::uint64_t>();
    r.triangles_truth = v.at("triangles_truth").get<std::uint64_t>();
    r.triangle_ratio = number_from(v, "triangle_ratio", kNaN);
    r.ms_impostor = number_from(v, "ms_impostor", kNaN);
    r.ms_truth = number_from(v, "ms_truth", kNaN);
    // Only with --lod-cut; a null PSNR is +infinity (identical images).
    if (v.contains("psnr_db_cut")) {
      r.psnr_db_cut = number_from(v, "psnr_db_cut", std::numeric_limits<double>::infinity());
      r.cut_error_px = number_from(v, "cut_error_px", kNaN);
      r.psnr_db_cut_1px = number_from(v, "psnr_db_cut_1px", std::numeric_limits<double>::infinity());
      r.triangles_cut_1px = number_from(v, "triangles_cut_1px", kNaN);
      r.psnr_gain_over_cut = psnr_difference(r.psnr_db, r.psnr_db_cut);
    }
    c.views.push_back(r);
  }
  return c;
}

nlohmann::json summary_json(const std::vector<VerifyCellResult>& cells) {
  nlohmann::json s;
  std::size_t views = 0, failed = 0, blank = 0;
  std::vector<double> bake, bytes, tri_imp, tri_truth;
  for (const auto& c : cells) {
    views += c.views.size();
    for (const auto& v : c.views) blank += v.truth_blank;
    failed += !c.error.empty();
    if (!c.error.empty()) continue;
    bake.push_back(c.bake_seconds_total());
    bytes.push_back(double(c.bytes));
    for (const auto& v : c.views) {
      if (!is_headline_view(v.kind)) continue;
      tri_imp.push_back(double(v.triangles_impostor));
      tri_truth.push_back(double(v.triangles_truth));
    }
  }
  s["cells"] = cells.size();
  s["cells_failed"] = failed;
  s["views"] = views;
  s["truth_blank_views"] = blank;
  for (const auto& m : verify_metrics()) {
    const MetricStats st = metric_stats(cells, m);
    s[m.name] = {{"count", st.count},
                 {"median", number_or_null(st.median)},
                 {"worst", number_or_null(st.worst)},
                 {"worst_cell", st.worst_cell},
                 {"worst_view", st.worst_view},
                 {"median_centre", number_or_null(st.median_centre)},
                 {"median_corner", number_or_null(st.median_corner)},
                 {"median_reference", number_or_null(st.median_reference)},
                 {"median_sample", number_or_null(st.median_sample)},
                 {"higher_is_better", m.higher_is_better}};
  }
  s["bake_seconds_median"] = number_or_null(median_of(bake));
  s["bytes_median"] = number_or_null(median_of(bytes));
  s["triangles_impostor_median"] = number_or_null(median_of(tri_imp));
  s["triangles_truth_median"] = number_or_null(median_of(tri_truth));
  return s;
}

void write_text_file_atomically(const std::filesystem::path& file, const std::string& text,
                                const InputFiles& inputs) {
  write_output_file(file, text, inputs);
}

namespace {

// report.json: {database, params, summary, cells[, walk]}.
void write_report_json(const std::filesystem::path& dir, const VerifyReportInput& input,
                       const nlohmann::json& summary, VerifyReportFiles& files) {
  nlohmann::json report{{"database", input.database}, {"params", input.params}, {"summary", summary}};
  report["cells"] = nlohmann::json::array();
  for (const auto& c : input.cells) report["cells"].push_back(to_json(c));
  if (input.walk) report["walk"] = input.walk->summary;
  files.json = dir / "report.json";
  write_text_file_atomically(files.json, report.dump(1), input.inputs);
}

// The plots of median PSNR per cell, against bake seconds and against stored bytes.
void write_per_cell_plots(const std::filesystem::path& dir, const VerifyReportInput& input, VerifyReportFiles& files) {
  const std::string psnr_label = "median PSNR per cell, dB (higher is better)";
  auto per_cell = [&](const std::string& name, const std::string& title, const std::string& x_label,
                      bool log_x, auto x_of) {
    ScatterPlot p{title, x_label, psnr_label, log_x, 640, 420, {}};
    PlotSeries s{"cells", "#1f77b4", {}};
    for (const auto& c : input.cells)
      if (c.error.empty())
        s.points.push_back(
            {x_of(c), cell_median(c, &VerifyViewResult::psnr_db), "cell " + std::to_string(c.id)});
    p.series.push_back(std::move(s));
    write_svg(dir / "plots" / name, scatter_plot_svg(p), files, input.inputs);
  };
  per_cell("psnr_vs_bake_seconds.svg", "Error vs bake time", "bake seconds per cell (all stages)", false,
           [](const VerifyCellResult& c) { return c.bake_seconds_total(); });
  per_cell("psnr_vs_bytes.svg", "Error vs stored bytes", "stored bytes per cell", false,
           [](const VerifyCellResult& c) { return double(c.bytes); });
}

// The plots per view: PSNR against triangles drawn, and PSNR and holes against
// the distance from the sample point when the views lie at 3 or more distinct
// distances (else they say nothing). Returns that number of distances.
std::size_t write_per_view_plots(const std::filesystem::path& dir, const VerifyReportInput& input,
                                 VerifyReportFiles& files) {
  const auto& cells = input.cells;
  {
    ScatterPlot p{"Error vs triangles drawn", "triangles drawn (impostor: near + far field)",
                  "PSNR per view, dB (higher is better)", false, 640, 420,
                  per_view_series(cells, [](const VerifyViewResult& v, const VerifyCellResult&) { return double(v.triangles_impostor); },
                                  [](const VerifyViewResult& v) { return v.psnr_db; })};
    write_svg(dir / "plots" / "psnr_vs_triangles.svg", scatter_plot_svg(p), files, input.inputs);
  }
  const std::size_t distances = distinct_sample_distances(cells);
  if (distances >= 3) {
    ScatterPlot p{"Error vs distance from the sample point", "eye distance from the nearest sample point (model units)",
                  "PSNR per view, dB (higher is better)", false, 640, 420,
                  per_view_series(cells, [](const VerifyViewResult& v, const VerifyCellResult&) { return v.distance_from_sample; },
                                  [](const VerifyViewResult& v) { return v.psnr_db; })};
    write_svg(dir / "plots" / "psnr_vs_distance.svg", scatter_plot_svg(p), files, input.inputs);
  }
  if (distances >= 3) {
    ScatterPlot p{"Holes vs distance from the sample point", "eye distance from the nearest sample point (model units)",
                  "hole fraction per view (lower is better)", false, 640, 420,
                  per_view_series(cells, [](const VerifyViewResult& v, const VerifyCellResult&) { return v.distance_from_sample; },
                                  [](const VerifyViewResult& v) { return v.hole_fraction; })};
    write_svg(dir / "plots" / "holes_vs_distance.svg", scatter_plot_svg(p), files, input.inputs);
  }
  return distances;
}

// The far-budget sweep's curve over the headline views drawn under several
// budgets (empty when none was), and the median triangles their truth draws.
struct FarBudgetSweep {
  std::vector<FarBudgetSummary> rows;
  double truth_triangles = kNaN;
};

// The sweep summarised, and its plot written when there is one.
FarBudgetSweep write_far_budget_sweep_plot(const std::filesystem::path& dir, const VerifyReportInput& input,
                                           VerifyReportFiles& files) {
  std::vector<std::vector<FarBudgetPoint>> sweep_views;
  std::vector<double> truth_triangles;
  for (const auto& c : input.cells)
    for (const auto& v : c.views)
      if (is_headline_view(v.kind) && !v.truth_blank && !v.far_budget_sweep.empty()) {
        sweep_views.push_back(v.far_budget_sweep);
        truth_triangles.push_back(double(v.triangles_truth));
      }
  FarBudgetSweep sweep;
  sweep.rows = summarise_far_budget_sweep(sweep_views);
  sweep.truth_triangles = median_of(truth_triangles);
  if (!sweep.rows.empty())
    write_svg(dir / "plots" / "psnr_vs_triangles_far_budget.svg",
              scatter_plot_svg(far_budget_sweep_plot(sweep.rows, sweep.truth_triangles)), files, input.inputs);
  return sweep;
}

// cell_map.svg: the cells in plan, coloured by median PSNR. Returns its SVG.
std::string write_cell_map(const std::filesystem::path& dir, const VerifyReportInput& input,
                           VerifyReportFiles& files) {
  // Drop the up axis (the one with the most cells sharing one value is not known
  // here, so use the database's up from params when given, else z).
  const std::string up = input.params.value("up", std::string("z"));
  const int a = up == "y" ? 2 : 0, b = up == "y" ? 0 : 1;  // y up: plan (z, x); z up: plan (x, y)
  CellMap map;
  map.title = "Cell map: median PSNR per cell";
  map.value_label = "median PSNR (dB)";
  map.scale_worst = kVerifyPsnrRed, map.scale_best = kVerifyPsnrGreen, map.scale_unit = " dB";
  std::vector<const VerifyCellResult*> order;
  for (const auto& c : input.cells) order.push_back(&c);
  // Worst cells last, so the worst of a stack of layers shows on top.
  std::stable_sort(order.begin(), order.end(), [](const VerifyCellResult* x, const VerifyCellResult* y) {
    const double px = cell_median(*x, &VerifyViewResult::psnr_db),
                 py = cell_median(*y, &VerifyViewResult::psnr_db);
    return (std::isnan(px) ? -1e300 : -px) < (std::isnan(py) ? -1e300 : -py);
  });
  for (const auto* c : order)
    map.cells.push_back({c->id, c->bounds.lo[a], c->bounds.lo[b], c->bounds.hi[a], c->bounds.hi[b],
                         cell_median(*c, &VerifyViewResult::psnr_db)});
  files.cell_map = dir / "cell_map.svg";
  const std::string cell_map = cell_map_svg(map);
  write_text_file_atomically(files.cell_map, cell_map, input.inputs);
  return cell_map;
}

// The HTML head (title, inline CSS) and the introduction: database,
// parameters, counts, lighting, blank truth views and what the metrics mean.
void html_introduction(std::ostringstream& h, const VerifyReportInput& input, const nlohmann::json& summary) {
  h << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>cellbake verify: "
    << escape_xml(input.database)
    << "</title>\n<style>\n"
       "body{font-family:sans-serif;margin:2em;color:#222;max-width:1400px}\n"
       "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:3px "
       "8px;text-align:right}\n"
       "th{background:#f0f0f0}td.l,th.l{text-align:left}tr.bad td{background:#fde2e2}\n"
       ".plots svg{margin:4px;border:1px solid #ddd}.trip img{max-width:100%;border:1px solid #ddd}\n"
       "code{background:#f4f4f4;padding:1px 4px}.note{color:#666;font-size:90%}\n"
       "</style></head><body>\n";
  h << "<h1>cellbake verify</h1>\n<p>Database <code>" << escape_xml(input.database)
    << "</code>; parameters <code>" << escape_xml(input.params.dump()) << "</code>. "
    << summary["cells"].get<std::size_t>() << " cells (" << summary["cells_failed"].get<std::size_t>()
    << " could not be verified), " << summary["views"].get<std::size_t>()
    << " views: each rendered as the cell's impostor (near field + textured depth meshes) and as ground "
       "truth.</p>\n";
  if (input.walk) h << "<p>A walk through the cells: <a href=\"#walk\">its video, plot and summary</a>.</p>\n";
  if (input.params.contains("lighting"))
    h << "<p>Lighting (truth and samples alike): " << escape_xml(input.params["lighting"].get<std::string>())
      << ".</p>\n";
  if (const std::size_t blank = summary["truth_blank_views"].get<std::size_t>(); blank > 0)
    h << "<p><b>Warning: " << blank << " of " << summary["views"].get<std::size_t>()
      << " truth views are blank</b> (one colour over every covered pixel, or nothing covered): their PSNR "
         "and SSIM "
         "say nothing about the bake. A black or single-colour model (check the ingest summary's vertex "
         "colours) "
         "or views that see nothing.</p>\n";
  h << "<p class=\"note\">PSNR and SSIM compare colours (higher is better); hole = truth surface the "
       "impostor "
       "misses, skin = impostor surface >5% nearer than the truth, extra = impostor surface where the truth "
       "is empty "
       "(fractions, lower is better); depth error = median relative depth error; ms = warm frame time of the "
       "software renderer while other views render in parallel.</p>\n";
}

// The Summary section: a row per measured metric (random views, then the
// reference views apart), and the median bake time, bytes and triangles per cell.
void html_summary(std::ostringstream& h, const std::vector<VerifyCellResult>& cells, const nlohmann::json& summary) {
  h << "<h2>Summary</h2>\n<p class=\"note\">The headline columns (median, worst, worst cell), the cell map, "
       "the "
       "per-cell figures and the worst views are over the <b>random views</b>: eyes drawn uniformly from "
       "each "
       "cell's navigable part, looking in uniformly random horizontal directions &mdash; what a person "
       "walking "
       "anywhere in the cell sees. The reference views are reported apart: the centre and corners of the "
       "navigable part and the cell's sample points, where the far field was sampled and is at its "
       "best.</p>\n"
       "<table><tr><th class=\"l\">metric</th><th>median</th><th>worst</th><th>worst cell</th>"
       "<th>median, centre views</th><th>median, corner views</th><th>median, views at sample points</th>"
       "<th>median, all reference views</th></tr>\n";
  for (const auto& m : verify_metrics()) {
    const MetricStats st = metric_stats(cells, m);
    if (st.count == 0 && std::isnan(st.median_reference)) continue;  // not measured (e.g. psnr_db_cut without --lod-cut)
    h << "<tr><td class=\"l\">" << m.name << "</td><td>" << fmt(st.median) << "</td><td>" << fmt(st.worst)
      << "</td><td>" << (st.count ? std::to_string(st.worst_cell) : "&ndash;") << "</td><td>"
      << fmt(st.median_centre) << "</td><td>" << fmt(st.median_corner) << "</td><td>" << fmt(st.median_sample)
      << "</td><td>" << fmt(st.median_reference) << "</td></tr>\n";
  }
  h << "</table>\n<p>Median per cell: bake "
    << fmt(summary["bake_seconds_median"].is_null() ? kNaN : summary["bake_seconds_median"].get<double>())
    << " s, " << fmt(summary["bytes_median"].is_null() ? kNaN : summary["bytes_median"].get<double>(), "%.0f")
    << " bytes stored; triangles drawn per view: impostor "
    << fmt(summary["triangles_impostor_median"].is_null()
               ? kNaN
               : summary["triangles_impostor_median"].get<double>(),
           "%.0f")
    << ", truth "
    << fmt(summary["triangles_truth_median"].is_null() ? kNaN
                                                       : summary["triangles_truth_median"].get<double>(),
           "%.0f")
    << ".</p>\n";
}

// The sections with pictures: the cell map, the far-budget sweep, the plots
// (read back from files.plots) and the walk. Everything inline: the report is
// one file that can be copied or mailed alone; inline SVG keeps the tooltips
// (<title>) that <img> would disable.
void html_figures(std::ostringstream& h, const std::filesystem::path& dir, const VerifyReportInput& input,
                  const VerifyReportFiles& files, const std::string& cell_map, const FarBudgetSweep& sweep,
                  std::size_t distances) {
  h << "<h2>Cell map</h2>\n<p class=\"note\">Fixed colour scale: median PSNR &le; " << kVerifyPsnrRed
    << " dB red, " << 0.5 * (kVerifyPsnrRed + kVerifyPsnrGreen) << " dB yellow, &ge; " << kVerifyPsnrGreen
    << " dB green; perfect cells (impostor = truth, PSNR = &infin;) dark green, labelled perfect; grey: no "
       "data. Hover a cell for its id and value.</p>\n<div class=\"map\"><!-- cell_map.svg -->\n"
    << inline_svg(cell_map) << "</div>\n";
  if (!sweep.rows.empty())
    h << "<h2>Speed against error: far budget swept</h2>\n<p class=\"note\">Every random view drawn once more "
         "per far-field budget (the nearest sample with its ancestors, then more samples while the far field's "
         "triangles stay under the budget); the truth draws a median of "
      << fmt(sweep.truth_triangles, "%.0f") << " triangles per view (frustum-culled).</p>\n"
      << far_budget_sweep_table_html(sweep.rows, sweep.truth_triangles);
  h << "<h2>Plots</h2>\n<div class=\"plots\">\n";
  for (const auto& p : files.plots) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream svg;
    svg << in.rdbuf();
    h << "<!-- plots/" << escape_xml(p.filename().string()) << " -->\n" << inline_svg(svg.str()) << "\n";
  }
  h << "</div>\n<p class=\"note\">Views whose impostor equals the truth exactly (PSNR = &infin;) are not "
       "drawn in "
       "PSNR plots.</p>\n";
  if (distances < 3)
    h << "<p class=\"note\">Error and holes vs distance from the sample point: not plotted, the views lie at "
      << distances << " distinct distance(s) from their cell's sample points (fewer than 3).</p>\n";
  if (input.walk) {
    std::ifstream plot_in(dir / input.walk->plot, std::ios::binary);
    std::ostringstream plot_svg;
    if (!input.walk->plot.empty() && plot_in) plot_svg << plot_in.rdbuf();
    h << walk_section_html(*input.walk, input.walk->worst_png.empty() ? "" : png_data_uri(dir / input.walk->worst_png),
                           plot_svg.str());
  }
}

// The Worst views section: each cell's worst view as a triptych, worst first,
// at most input.worst_views of them.
void html_worst_views(std::ostringstream& h, const std::filesystem::path& dir, const VerifyReportInput& input) {
  std::vector<const VerifyCellResult*> worst;
  for (const auto& c : input.cells)
    if (c.worst_view >= 0 && c.worst_view < int(c.views.size()) && !c.triptych.empty()) worst.push_back(&c);
  std::stable_sort(worst.begin(), worst.end(), [](const VerifyCellResult* x, const VerifyCellResult* y) {
    const auto &vx = x->views[x->worst_view], &vy = y->views[y->worst_view];
    return vx.psnr_db < vy.psnr_db || (vx.psnr_db == vy.psnr_db && vx.hole_fraction > vy.hole_fraction);
  });
  if (int(worst.size()) > input.worst_views) worst.resize(std::max(0, input.worst_views));
  h << "<h2>Worst views</h2>\n<p class=\"note\">Left to right: ground truth, impostor, error image (magenta "
       "hole, "
       "yellow skin, cyan extra surface, blue&rarr;green&rarr;red colour error).</p>\n";
  for (const auto* c : worst) {
    const auto& v = c->views[c->worst_view];
    h << "<div class=\"trip\"><h3>cell " << c->id << ", view " << c->worst_view << " ("
      << view_kind_name(v.kind) << "): PSNR " << fmt(v.psnr_db, "%.2f") << " dB, SSIM " << fmt(v.ssim, "%.3f")
      << ", holes " << fmt(v.hole_fraction, "%.4f") << ", skins " << fmt(v.skin_fraction, "%.4f")
      << "</h3>\n<p class=\"note\">eye (" << fmt(v.eye.x, "%.3f") << ", " << fmt(v.eye.y, "%.3f") << ", "
      << fmt(v.eye.z, "%.3f") << "), look (" << fmt(v.look.x, "%.3f") << ", " << fmt(v.look.y, "%.3f") << ", "
      << fmt(v.look.z, "%.3f") << "), " << fmt(v.distance_from_sample, "%.3f")
      << " from the sample point</p>\n<img src=\"" << png_data_uri(dir / c->triptych) << "\" alt=\"cell "
      << c->id << " (" << escape_xml(c->triptych) << ")\"></div>\n";
  }
}

// The median over a cell's views of a count field (all its views, blank ones included).
double views_median(const VerifyCellResult& c, std::uint64_t VerifyViewResult::*field) {
  std::vector<double> v;
  for (auto& x : c.views) v.push_back(double(x.*field));
  return median_of(v);
}

// One row of the Cells table; `bad` marks a failed cell or the worst one.
void html_cell_row(std::ostringstream& h, const VerifyCellResult& c, bool bad) {
  std::vector<double> psnr, holes, skins;
  for (const auto& v : c.views)
    psnr.push_back(v.psnr_db), holes.push_back(v.hole_fraction), skins.push_back(v.skin_fraction);
  const double min_psnr = psnr.empty() ? kNaN : *std::min_element(psnr.begin(), psnr.end());
  const double max_ratio = max_of(c, &VerifyViewResult::triangle_ratio);
  h << "<tr" << (bad ? " class=\"bad\"" : "") << "><td>" << c.id << "</td><td>" << c.views.size()
    << "</td><td>" << fmt(cell_median(c, &VerifyViewResult::psnr_db), "%.2f") << "</td><td>"
    << fmt(min_psnr, "%.2f") << "</td><td>" << fmt(cell_median(c, &VerifyViewResult::ssim), "%.3f")
    << "</td><td>" << fmt(holes.empty() ? kNaN : *std::max_element(holes.begin(), holes.end()), "%.4f")
    << "</td><td>" << fmt(skins.empty() ? kNaN : *std::max_element(skins.begin(), skins.end()), "%.4f")
    << "</td><td>" << fmt(cell_median(c, &VerifyViewResult::depth_error_median), "%.4f") << "</td><td>"
    << fmt(views_median(c, &VerifyViewResult::triangles_impostor), "%.0f") << "</td><td>"
    << fmt(views_median(c, &VerifyViewResult::triangles_truth), "%.0f")
    << "</td><td>" << fmt(max_ratio, "%.2f") << (max_ratio > 1 ? " (draws more than the model)" : "")
    << "</td><td>" << c.far_triangles << " / " << c.far_geometry_triangles << "</td><td>"
    << fmt(cell_median(c, &VerifyViewResult::ms_impostor), "%.1f") << "</td><td>"
    << fmt(cell_median(c, &VerifyViewResult::ms_truth), "%.1f") << "</td><td>"
    << fmt(c.bake_seconds_total(), "%.2f") << "</td><td>" << c.bytes << "</td><td>"
    << fmt(c.colour_bytes / 1024.0, "%.1f") << " / " << fmt(c.mesh_bytes / 1024.0, "%.1f") << " / "
    << fmt(c.near_list_bytes / 1024.0, "%.1f") << "</td><td>" << c.void_curve.size() << "</td><td>"
    << fmt(cell_median(c, &VerifyViewResult::psnr_db_root), "%.2f") << "</td><td>"
    << fmt(max_of(c, &VerifyViewResult::hole_fraction_root), "%.4f") << "</td><td class=\"l\">"
    << void_curve_text(c) << "</td><td class=\"l\">" << escape_xml(c.error) << "</td></tr>\n";
}

// The Cells table, a row per cell (the worst cell's and failed ones marked),
// and the page's end.
void html_cells_table(std::ostringstream& h, const std::vector<VerifyCellResult>& cells) {
  h << "<h2>Cells</h2>\n<table><tr><th>cell</th><th>views</th><th>median PSNR</th><th>min "
       "PSNR</th><th>median SSIM</th>"
       "<th>max holes</th><th>max skins</th><th>median depth err</th><th>tris impostor</th><th>tris "
       "truth</th>"
       "<th>max tris impostor / truth</th><th>far tris stored: depth meshes / geometry</th>"
       "<th>ms impostor</th><th>ms truth</th><th>bake s</th><th>bytes</th><th>KB colour / mesh / near "
       "list</th><th>samples</th>"
       "<th>median PSNR, root sample alone</th><th>max holes, root sample alone</th>"
       "<th class=\"l\">void curve (after each sample)</th><th class=\"l\">note</th></tr>\n";
  const MetricStats psnr_stats = metric_stats(cells, verify_metrics()[0]);
  for (const auto& c : cells)
    html_cell_row(h, c, !c.error.empty() || (psnr_stats.count && c.id == psnr_stats.worst_cell));
  h << "</table>\n<p class=\"note\">Per-view numbers: <a "
       "href=\"report.json\">report.json</a>.</p>\n</body></html>\n";
}

}  // namespace

VerifyReportFiles write_verify_report(const std::filesystem::path& dir, const VerifyReportInput& input) {
  VerifyReportFiles files;
  std::filesystem::create_directories(dir / "plots");
  const nlohmann::json summary = summary_json(input.cells);
  write_report_json(dir, input, summary, files);
  write_per_cell_plots(dir, input, files);
  const std::size_t distances = write_per_view_plots(dir, input, files);
  const FarBudgetSweep sweep = write_far_budget_sweep_plot(dir, input, files);
  const std::string cell_map = write_cell_map(dir, input, files);

  std::ostringstream h;
  html_introduction(h, input, summary);
  html_summary(h, input.cells, summary);
  html_figures(h, dir, input, files, cell_map, sweep, distances);
  html_worst_views(h, dir, input);
  html_cells_table(h, input.cells);
  files.html = dir / "report.html";
  write_text_file_atomically(files.html, h.str(), input.inputs);
  return files;
}

}  // namespace cellbake
