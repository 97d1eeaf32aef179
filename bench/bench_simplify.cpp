// Simplification of one dense 512^2 depth-mesh face: ours vs meshoptimizer's
// meshopt_simplify and OpenMesh's quadric Decimater at the same triangle count,
// on two scenes (range `scene`): 0 = an analytic room with boxes and pipes at
// several depths, 1 = a "pipe array" (40 thin pipes, 2-6 px wide, seen from
// below against a ceiling: outline-dominated). Counters: output triangles and
// the error each achieved, measured with one ruler
// (measure_simplification_error): max relative depth error at the dense
// vertices off outlines, max outline displacement in px, screen-coverage
// samples lost / gained (4 per pixel), screen-space flipped triangles. The
// cost of build_depth_meshes is in bench_depth_mesh.
// OpenMesh takes ~10 s per face: it runs one iteration on scene 0 only.
#include <benchmark/benchmark.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <meshoptimizer.h>

#include <cmath>

#include "bench/bench_room_scene.h"
#include "pipeline/scenes/depth_mesh_analytic_scene.h"
#include "stages/depth_mesh.h"
#include "stages/simplify/simplify.h"

namespace {

using namespace cellbake;

constexpr int kSize = 512;

const CubeSample& room_sample() {
  static const CubeSample sample = bench_room_sample(kSize);
  return sample;
}

// 40 vertical pipes below a ceiling, seen from underneath (+Z face): slanted
// radial bands 2-6 px wide.
FaceMesh pipe_array_face() {
  AnalyticScene scene;
  scene.boxes.push_back({{-60, -60, 30}, {60, 60, 31}});
  for (int k = 0; k < 40; ++k) {
    const double angle = 0.157 * k + 0.03 * (k % 3), rho = 3.0 + 0.1 * (k % 11);
    scene.cylinders.push_back({rho * std::cos(angle), rho * std::sin(angle), 0.1, 8.0 + 0.1 * (k % 5), 29.0});
  }
  return build_depth_meshes(raycast_analytic_scene(scene, {0, 0, 0}, kSize), DepthMeshParams{})[4];
}

const FaceMesh& dense_face(int scene) {
  static const FaceMesh room = build_depth_meshes(room_sample(), DepthMeshParams{})[0];  // +X
  static const FaceMesh pipes = pipe_array_face();
  return scene == 0 ? room : pipes;
}

void report(benchmark::State& state, int scene, const FaceMesh& out) {
  const SimplifyError e = measure_simplification_error(dense_face(scene), out, kSize);
  state.counters["tris_in"] = double(dense_face(scene).triangle_count());
  state.counters["tris_out"] = double(out.triangle_count());
  state.counters["max_depth_err_rel"] = e.max_depth_error_relative;
  state.counters["boundary_err_px"] = e.max_boundary_error_px;
  state.counters["uncovered_samples"] = double(e.uncovered_samples);
  state.counters["spurious_samples"] = double(e.spurious_samples);
  state.counters["flipped_tris"] = double(e.flipped_triangles);
}

// capped = 1: the default 10,000-triangle cap (relaxes the interior bound, retrying);
// capped = 0: no cap (one pass at depth_error_relative = 0.01).
SimplifyParams our_params(bool capped = false) {
  SimplifyParams p;
  p.depth_error_relative = 0.01;
  if (!capped) p.max_triangles = std::size_t(1) << 40;
  return p;
}

// The other methods are asked for as many triangles as ours makes uncapped.
std::size_t our_triangle_count(int scene) {
  static const std::array<std::size_t, 2> count{simplify_face_mesh(dense_face(0), kSize, our_params()).triangles_out,
                                                simplify_face_mesh(dense_face(1), kSize, our_params()).triangles_out};
  return count[scene];
}

void BM_Ours(benchmark::State& state) {
  const int scene = int(state.range(0));
  const FaceMesh& in = dense_face(scene);
  SimplifyResult r;
  for (auto _ : state) {
    r = simplify_face_mesh(in, kSize, our_params(state.range(1) != 0));  // includes measuring its own error
    benchmark::DoNotOptimize(r.mesh.indices.data());
  }
  report(state, scene, r.mesh);
  state.counters["bound_used"] = r.depth_error_bound_used;
}

void BM_Meshoptimizer(benchmark::State& state) {
  const int scene = int(state.range(0));
  const FaceMesh& in = dense_face(scene);
  const unsigned options = state.range(1) ? meshopt_SimplifyLockBorder : 0;
  FaceMesh out;
  out.positions = in.positions;
  out.uvs = in.uvs;
  for (auto _ : state) {
    out.indices.resize(in.indices.size());
    float achieved = 0;
    const std::size_t count =
        meshopt_simplify(out.indices.data(), in.indices.data(), in.indices.size(), &in.positions[0].x, in.positions.size(),
                         sizeof(Vec3f), our_triangle_count(scene) * 3, 1.0f, options, &achieved);
    out.indices.resize(count);
    benchmark::DoNotOptimize(out.indices.data());
  }
  report(state, scene, out);
}

void BM_OpenMeshDecimater(benchmark::State& state) {
  using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;
  const FaceMesh& in = dense_face(0);
  FaceMesh out;
  for (auto _ : state) {
    Mesh mesh;
    std::vector<Mesh::VertexHandle> vh;
    vh.reserve(in.positions.size());
    for (const Vec3f& p : in.positions) vh.push_back(mesh.add_vertex({p.x, p.y, p.z}));
    for (std::size_t t = 0; t < in.triangle_count(); ++t)
      mesh.add_face(vh[in.indices[3 * t]], vh[in.indices[3 * t + 1]], vh[in.indices[3 * t + 2]]);
    OpenMesh::Decimater::DecimaterT<Mesh> decimater(mesh);
    OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
    decimater.add(quadric);
    decimater.module(quadric).unset_max_err();
    decimater.initialize();
    decimater.decimate_to_faces(0, our_triangle_count(0));
    mesh.garbage_collection();
    state.PauseTiming();
    out = {};
    std::vector<std::uint32_t> remap(mesh.n_vertices());
    for (auto v : mesh.vertices()) {
      // Vertices keep input positions (half-edge collapses): find the uv by position.
      remap[v.idx()] = std::uint32_t(out.positions.size());
      const auto p = mesh.point(v);
      out.positions.push_back({p[0], p[1], p[2]});
    }
    state.ResumeTiming();
    for (auto f : mesh.faces())
      for (auto v : f.vertices()) out.indices.push_back(remap[v.idx()]);
  }
  // uvs by position lookup (outside the timing): dense positions are unique per lattice point and component.
  std::vector<std::pair<std::array<float, 3>, Uv>> lookup;
  for (std::size_t v = 0; v < in.positions.size(); ++v)
    lookup.push_back({{in.positions[v].x, in.positions[v].y, in.positions[v].z}, in.uvs[v]});
  std::sort(lookup.begin(), lookup.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const Vec3f& p : out.positions) {
    const std::array<float, 3> key{p.x, p.y, p.z};
    auto it = std::lower_bound(lookup.begin(), lookup.end(), key, [](const auto& a, const auto& k) { return a.first < k; });
    out.uvs.push_back(it != lookup.end() && it->first == key ? it->second : Uv{});
  }
  report(state, 0, out);
}

BENCHMARK(BM_Ours)->ArgsProduct({{0, 1}, {0, 1}})->ArgNames({"scene", "capped"})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Meshoptimizer)->ArgsProduct({{0, 1}, {0, 1}})->ArgNames({"scene", "lock_border"})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenMeshDecimater)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
