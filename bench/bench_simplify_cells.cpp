// Simplification of real cube faces, side by side with meshoptimizer: for each
// selected cell of a bake configuration, runs the cull box, the sample and the
// depth meshes once (as `cellbake bake` does), then times, per face,
//  * ours       - simplify_face_mesh with the configuration's parameters;
//  * meshopt    - meshopt_simplify of the same dense face to the same
//                 triangle count (error target 1e-2, locked borders: the
//                 outlines and skins are mesh borders, so they stay exact
//                 and meshopt may stop above the count);
// and measures both with one ruler (measure_simplification_error). Also times
// what a bake spends measuring a kept face (`measure_ms`: SimplifyRuler::measure
// on our result, the analysis already held). Prints one row per face and a
// summary: total seconds, the speed ratio, the worst boundary error and the
// faces above the triangle cap.
//
//   cellbake demo --out /tmp/demo
//   bench_simplify_cells /tmp/demo/plant-demo.toml --store /tmp/demo/plant.store.db --cells 20-27 --repeat 3
//
// Not a Google Benchmark program: it needs a geometry store and reports
// per-face error figures next to the times.
#include <CLI/CLI.hpp>

#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/bench_program.h"
#include "pipeline/bake_config.h"
#include "pipeline/cell_grid.h"
#include "pipeline/cell_job.h"
#include "pipeline/sample_backend.h"
#include "stages/depth_mesh.h"
#include "stages/simplify/simplify.h"
#include "storage/geometry_store.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

struct Args {
  std::string config, store, cells = "1-8";
  int repeat = 3;
  bool meshopt = true;
};

Args parse_args(int argc, char** argv) {
  Args a;
  bool no_meshopt = false;
  CLI::App app{"Our simplifier against meshopt_simplify on the dense faces of baked cells", "bench_simplify_cells"};
  app.add_option("config", a.config, "Bake configuration (TOML)")->required();
  app.add_option("--store", a.store, "Geometry store (default: the configuration's)");
  app.add_option("--cells", a.cells, "Cells to sample and simplify")->capture_default_str();
  app.add_option("--repeat", a.repeat, "Timed repetitions")->check(CLI::PositiveNumber)->capture_default_str();
  app.add_flag("--no-meshopt", no_meshopt, "Skip the meshopt_simplify comparison");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::exit(app.exit(e));
  }
  a.meshopt = !no_meshopt;
  return a;
}

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// meshopt_simplify of a dense face to `target` triangles; positions as floats.
FaceMesh meshopt_face(const FaceMesh& in, std::size_t target) {
  std::vector<float> xyz;
  xyz.reserve(in.positions.size() * 3);
  for (const Vec3f& p : in.positions) xyz.insert(xyz.end(), {p.x, p.y, p.z});
  std::vector<std::uint32_t> out(in.indices.size());
  const std::size_t n = meshopt_simplify(out.data(), in.indices.data(), in.indices.size(), xyz.data(),
                                         in.positions.size(), sizeof(float) * 3, target * 3, 1e-2f,
                                         meshopt_SimplifyLockBorder, nullptr);
  FaceMesh m;
  m.positions = in.positions;
  m.uvs = in.uvs;
  m.indices.assign(out.begin(), out.begin() + std::ptrdiff_t(n));
  return m;
}

int run(int argc, char** argv) {
  const Args args = parse_args(argc, argv);
  if (!std::getenv("LP_NUM_THREADS")) setenv("LP_NUM_THREADS", "1", 1);
  BakeConfig config = load_bake_config(args.config);
  if (!args.store.empty()) config.store = args.store;
  config.samples_initial = "centre";  // the cell-centre sample alone: whole faces, no delta scans
  config.samples_max = 1;
  GeometryStore store(config.store);
  const std::unique_ptr<CubeSampler> sampler =
      CubeSamplerFactory(parse_sample_backend(config.sample_backend), std::size_t(config.embree_cache_mb) << 20).make();
  SimplifyParams params;
  params.depth_error_relative = config.depth_error_relative;
  params.boundary_error_px = config.boundary_error_px;
  params.max_triangles = std::size_t(config.max_face_triangles);

  double ours_total = 0, meshopt_total = 0, measure_total = 0, worst_boundary = 0, worst_depth = 0;
  std::size_t faces = 0, over_cap = 0, tris_total = 0, outline_total = 0, outline_above = 0;
  std::printf("%5s %4s %8s %7s %9s %10s %9s %8s %6s %7s %9s %10s %9s %6s\n", "cell", "face", "dense", "ours", "ours_ms",
              "measure_ms", "depth_err", "bnd_px", "flips", "mopt", "mopt_ms", "mopt_depth", "mopt_bnd", "flips");
  for (const CellSpec& cell : select_cells(enumerate_cells(config.regions, config.cell_size), args.cells)) {
    CellWork work;
    work.cell = cell;
    run_cull_box(work, config, store);
    run_sample(work, config, store, *sampler);
    run_sample_tree(work, config);
    DepthMeshParams mesh_params;
    mesh_params.skin_angle_degrees = config.skin_angle_deg;
    mesh_params.max_relative_depth_jump = config.depth_jump;
    const std::array<FaceMesh, kCubeFaces> dense_faces = build_depth_meshes(work.samples.at(0).cube, mesh_params);
    for (int f = 0; f < kCubeFaces; ++f) {
      const FaceMesh& dense = dense_faces[std::size_t(f)];
      if (dense.indices.empty()) continue;
      std::vector<double> ours_s, mopt_s;
      SimplifyResult r;
      for (int k = 0; k < args.repeat; ++k) {
        const auto t0 = Clock::now();
        r = simplify_face_mesh(dense, config.face_size, params);
        ours_s.push_back(seconds_since(t0));
      }
      // The bake's measuring of a kept face: a ruler from finish(ruler), then measure().
      std::vector<double> measure_s;
      {
        SimplifyParams unmeasured = params;
        unmeasured.measure_error = false;
        SimplifyRuler ruler;
        const SimplifyResult kept = FaceSimplification(dense, config.face_size, unmeasured).finish(ruler);
        for (int k = 0; k < args.repeat; ++k) {
          const auto t0 = Clock::now();
          const SimplifyError e = ruler.measure(kept.mesh);
          measure_s.push_back(seconds_since(t0));
          if (e.max_boundary_error_px != r.achieved.max_boundary_error_px ||
              e.max_depth_error_relative != r.achieved.max_depth_error_relative)
            throw std::runtime_error("cell " + std::to_string(cell.id) + " face " + std::to_string(f) +
                                     ": the ruler measured other figures than simplify_face_mesh");
        }
      }
      measure_total += median(measure_s);
      double mopt_ms = 0;
      SimplifyError mopt_err;
      std::size_t mopt_tris = 0;
      if (args.meshopt) {
        FaceMesh m;
        for (int k = 0; k < args.repeat; ++k) {
          const auto t0 = Clock::now();
          m = meshopt_face(dense, std::max<std::size_t>(1, r.triangles_out));
          mopt_s.push_back(seconds_since(t0));
        }
        mopt_ms = 1e3 * median(mopt_s);
        mopt_err = measure_simplification_error(dense, m, config.face_size);
        mopt_tris = m.triangle_count();
        meshopt_total += median(mopt_s);
      }
      const double ours = median(ours_s);
      ours_total += ours;
      ++faces;
      tris_total += r.triangles_out;
      outline_total += r.outline_triangles;
      if (r.outline_triangles > r.triangles_out) ++outline_above;
      if (r.triangles_out > params.max_triangles) ++over_cap;
      worst_boundary = std::max(worst_boundary, r.achieved.max_boundary_error_px);
      worst_depth = std::max(worst_depth, r.achieved.max_depth_error_relative);
      std::printf("%5lld %4d %8zu %7zu %9.1f %10.2f %9.4f %8.2f %6zu %7zu %9.1f %10.4f %9.2f %6zu\n",
                  static_cast<long long>(cell.id), f, r.triangles_in, r.triangles_out, 1e3 * ours,
                  1e3 * median(measure_s),
                  r.achieved.max_depth_error_relative, r.achieved.max_boundary_error_px, r.achieved.flipped_triangles,
                  mopt_tris, mopt_ms, mopt_err.max_depth_error_relative, mopt_err.max_boundary_error_px,
                  mopt_err.flipped_triangles);
    }
  }
  std::printf("faces %zu, ours %.3f s (%.1f ms/face), measuring %.1f ms/face, meshopt %.3f s, ours/meshopt %.2f, "
              "triangles %zu, over cap %zu, worst boundary %.2f px, worst depth %.4f\n",
              faces, ours_total, faces ? 1e3 * ours_total / faces : 0.0, faces ? 1e3 * measure_total / faces : 0.0,
              meshopt_total,
              meshopt_total > 0 ? ours_total / meshopt_total : 0.0, tris_total, over_cap, worst_boundary, worst_depth);
  std::printf("outline-only triangulations: %zu triangles, %.1f %% of the result (faces where that exceeds the "
              "result: %zu)\n",
              outline_total, tris_total ? 100.0 * double(outline_total) / double(tris_total) : 0.0, outline_above);
  return 0;
}

}  // namespace
}  // namespace cellbake

int main(int argc, char** argv) {
  return cellbake::run_bench_program("bench_simplify_cells", cellbake::run, argc, argv);
}
