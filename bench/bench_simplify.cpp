// Simplification of one dense 512^2 depth-mesh face (an analytic room with
// boxes and pipes at several depths, ~half a million triangles): ours vs
// meshoptimizer's meshopt_simplify and OpenMesh's quadric Decimater at the same
// triangle count. Counters: output triangles and the error each achieved,
// measured with one ruler (measure_simplification_error): max relative depth
// error at the dense vertices, screen-coverage samples lost / gained (4 per
// pixel), screen-space flipped triangles.
#include <benchmark/benchmark.h>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <meshoptimizer.h>

#include "stages/depth_mesh.h"
#include "stages/depth_mesh_analytic_scene.h"
#include "stages/simplify.h"

namespace {

using namespace cellbake;

constexpr int kSize = 512;

const FaceMesh& dense_face() {
  static const FaceMesh face = [] {
    AnalyticScene scene;
    scene.boxes.push_back(Box3d::cube({0, 0, 0}, 30.0));
    scene.boxes.push_back({{4, -3, -6}, {6, 2, 1}});
    scene.boxes.push_back({{12, 3, -30}, {14, 9, 4}});
    scene.boxes.push_back({{20, -12, -8}, {24, -4, 12}});
    for (int k = 0; k < 6; ++k) scene.cylinders.push_back({7.0 + 3 * k, -8.0 + 3.1 * k, 0.08 + 0.05 * k, -30, 30});
    scene.cylinders.push_back({9, 5, 1.5, -30, 2});
    const CubeSample sample = raycast_analytic_scene(scene, {0.2, 0.1, 0.3}, kSize);
    return build_depth_meshes(sample, DepthMeshParams{})[0];  // +X
  }();
  return face;
}

void report(benchmark::State& state, const FaceMesh& out) {
  const SimplifyError e = measure_simplification_error(dense_face(), out, kSize);
  state.counters["tris_in"] = double(dense_face().triangle_count());
  state.counters["tris_out"] = double(out.triangle_count());
  state.counters["max_depth_err_rel"] = e.max_depth_error_relative;
  state.counters["uncovered_samples"] = double(e.uncovered_samples);
  state.counters["spurious_samples"] = double(e.spurious_samples);
  state.counters["flipped_tris"] = double(e.flipped_triangles);
}

// range 0: the default 10,000-triangle cap (relaxes the interior bound, retrying);
// range 1: no cap (one pass at depth_error_relative = 0.01).
SimplifyParams our_params(bool capped = false) {
  SimplifyParams p;
  p.depth_error_relative = 0.01;
  if (!capped) p.max_triangles = std::size_t(1) << 40;
  return p;
}

std::size_t our_triangle_count() {
  static const std::size_t count = simplify_face_mesh(dense_face(), kSize, our_params()).triangles_out;
  return count;
}

void BM_Ours(benchmark::State& state) {
  const FaceMesh& in = dense_face();
  SimplifyResult r;
  for (auto _ : state) {
    r = simplify_face_mesh(in, kSize, our_params(state.range(0) != 0));  // includes measuring its own error
    benchmark::DoNotOptimize(r.mesh.indices.data());
  }
  report(state, r.mesh);
  state.counters["bound_used"] = r.depth_error_bound_used;
}

void BM_Meshoptimizer(benchmark::State& state) {
  const FaceMesh& in = dense_face();
  const unsigned options = state.range(0) ? meshopt_SimplifyLockBorder : 0;
  FaceMesh out;
  out.positions = in.positions;
  out.uvs = in.uvs;
  for (auto _ : state) {
    out.indices.resize(in.indices.size());
    float achieved = 0;
    const std::size_t count =
        meshopt_simplify(out.indices.data(), in.indices.data(), in.indices.size(), &in.positions[0].x, in.positions.size(),
                         sizeof(Vec3f), our_triangle_count() * 3, 1.0f, options, &achieved);
    out.indices.resize(count);
    benchmark::DoNotOptimize(out.indices.data());
  }
  report(state, out);
}

void BM_OpenMeshDecimater(benchmark::State& state) {
  using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;
  const FaceMesh& in = dense_face();
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
    decimater.decimate_to_faces(0, our_triangle_count());
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
  report(state, out);
}

BENCHMARK(BM_Ours)->Arg(0)->Arg(1)->ArgName("capped")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Meshoptimizer)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->ArgName("lock_border");
BENCHMARK(BM_OpenMeshDecimater)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
