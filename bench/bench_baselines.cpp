// Baselines side by side with the cell impostors (Wilson 2002, ch. 7 compares
// textured depth meshes with geometric LOD): for each selected cell of a baked
// database, at the verify viewpoints (runner/verify/verify_views.h), draws
//  * truth     - every chunk in the frustum;
//  * impostor  - the cell's near field + textured depth meshes (cellbake);
//  * lod-meshopt    - the same near field + the whole far field (every triangle
//                     not wholly inside the cull box) simplified with
//                     meshopt_simplify to the cell's far_triangles budget
//                     (meshopt_simplifySloppy when the topology stops it short);
//  * lod-openmesh   - the same with OpenMesh's quadric Decimater (only when the
//                     far field has at most --decimater-max triangles: slow);
// all with the same renderer (ChunkRenderer / SceneDrawer) and compared with
// the truth by the same metrics (viewer/image_metrics.h). Prints one table of
// medians over views: method, triangles, PSNR, SSIM, holes, skins, ms.
//
//   cellbake demo --out /tmp/verify-demo --triangles 500000 --set sample.face_size=256
//   bench_baselines /tmp/verify-demo/cells.db --cells 1,32,63 --views 4 --size 320x240
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <meshoptimizer.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/bench_program.h"
#include "pipeline/cell_grid.h"
#include "runner/verify/verify_report.h"
#include "runner/verify/verify_views.h"
#include "stages/sample/sample_points.h"
#include "stages/render/chunk_renderer.h"
#include "stages/render/gl_context.h"
#include "storage/cell_db.h"
#include "storage/geometry_store.h"
#include "viewer/baked_config_text.h"
#include "viewer/camera_path.h"
#include "viewer/cell_index.h"
#include "viewer/decoded_cell.h"
#include "viewer/image_metrics.h"
#include "viewer/scene_drawer.h"
#include "viewer/view_camera.h"

namespace cellbake {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// A far field as one indexed mesh, positions relative to `origin` (float).
struct FarMesh {
  Vec3d origin;
  std::vector<Vec3f> positions;
  std::vector<Rgba8> colors;
  std::vector<std::uint32_t> indices;
};

bool inside(const Box3d& b, const Vec3d& p) {
  return p.x >= b.lo.x && p.x <= b.hi.x && p.y >= b.lo.y && p.y <= b.hi.y && p.z >= b.lo.z && p.z <= b.hi.z;
}

// Every triangle of the store not wholly inside `cull_box`, welded by position.
FarMesh far_field(const GeometryStore& store, const Box3d& cull_box, const Vec3d& origin) {
  FarMesh raw;
  raw.origin = origin;
  for (const ChunkRef& ref : store.query(store.model_bounds())) {
    const auto chunk = store.load(ref.id);
    for (std::size_t t = 0; t < chunk->triangle_count(); ++t) {
      const std::uint32_t* tri = &chunk->indices[3 * t];
      if (inside(cull_box, chunk->world(tri[0])) && inside(cull_box, chunk->world(tri[1])) &&
          inside(cull_box, chunk->world(tri[2])))
        continue;
      for (int k = 0; k < 3; ++k) {
        const Vec3d p = chunk->world(tri[k]) - origin;  // camera-relative: double, then float
        raw.positions.push_back({float(p.x), float(p.y), float(p.z)});
        raw.colors.push_back(chunk->colors[tri[k]]);
        raw.indices.push_back(std::uint32_t(raw.indices.size()));
      }
    }
  }
  // Weld equal positions (chunks and triangles share corners) so the simplifier sees connectivity.
  std::vector<unsigned> remap(raw.positions.size());
  const std::size_t unique = meshopt_generateVertexRemap(remap.data(), raw.indices.data(), raw.indices.size(),
                                                         raw.positions.data(), raw.positions.size(), sizeof(Vec3f));
  FarMesh out;
  out.origin = origin;
  out.positions.resize(unique);
  out.colors.resize(unique);
  meshopt_remapVertexBuffer(out.positions.data(), raw.positions.data(), raw.positions.size(), sizeof(Vec3f), remap.data());
  meshopt_remapVertexBuffer(out.colors.data(), raw.colors.data(), raw.colors.size(), sizeof(Rgba8), remap.data());
  out.indices.resize(raw.indices.size());
  meshopt_remapIndexBuffer(out.indices.data(), raw.indices.data(), raw.indices.size(), remap.data());
  return out;
}

std::shared_ptr<const Chunk> as_chunk(const FarMesh& m, std::vector<std::uint32_t> indices) {
  auto c = std::make_shared<Chunk>();
  c->id = -1;
  c->origin = m.origin;
  c->positions = m.positions;
  c->colors = m.colors;
  c->indices = std::move(indices);
  for (const auto& p : c->positions) c->bounds.expand(m.origin + Vec3d{p.x, p.y, p.z});
  return c;
}

// meshopt_simplify to `target` triangles, sloppy when the topology stops it above 1.1 x target.
std::vector<std::uint32_t> simplify_meshopt(const FarMesh& m, std::size_t target, bool& sloppy) {
  std::vector<std::uint32_t> out(m.indices.size());
  const float* pos = &m.positions[0].x;
  std::size_t n = meshopt_simplify(out.data(), m.indices.data(), m.indices.size(), pos, m.positions.size(),
                                   sizeof(Vec3f), 3 * target, 1.0f, 0, nullptr);
  sloppy = n > 3 * target * 11 / 10;
  if (sloppy)
    n = meshopt_simplifySloppy(out.data(), m.indices.data(), m.indices.size(), pos, m.positions.size(), sizeof(Vec3f),
                               3 * target, 1.0f, nullptr);
  out.resize(n);
  return out;
}

using OmMesh = OpenMesh::TriMesh_ArrayKernelT<>;

// OpenMesh quadric decimation to `target` faces. Non-manifold input faces are
// dropped by OpenMesh on insertion (counted in `dropped`).
std::shared_ptr<const Chunk> simplify_openmesh(const FarMesh& m, std::size_t target, std::size_t& dropped) {
  OmMesh mesh;
  mesh.request_vertex_colors();
  std::vector<OmMesh::VertexHandle> handles;
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    handles.push_back(mesh.add_vertex({m.positions[i].x, m.positions[i].y, m.positions[i].z}));
    mesh.set_color(handles.back(), {m.colors[i].r, m.colors[i].g, m.colors[i].b});
  }
  dropped = 0;
  for (std::size_t t = 0; t < m.indices.size(); t += 3) {
    const auto f = mesh.add_face(handles[m.indices[t]], handles[m.indices[t + 1]], handles[m.indices[t + 2]]);
    dropped += !f.is_valid();
  }
  OpenMesh::Decimater::DecimaterT<OmMesh> decimater(mesh);
  OpenMesh::Decimater::ModQuadricT<OmMesh>::Handle quadric;
  decimater.add(quadric);
  decimater.module(quadric).unset_max_err();
  decimater.initialize();
  decimater.decimate_to_faces(0, target);
  mesh.garbage_collection();
  FarMesh out;
  out.origin = m.origin;
  for (const auto& v : mesh.vertices()) {
    const auto p = mesh.point(v);
    const auto c = mesh.color(v);
    out.positions.push_back({p[0], p[1], p[2]});
    out.colors.push_back({c[0], c[1], c[2], 255});
  }
  std::vector<std::uint32_t> indices;
  for (const auto& f : mesh.faces())
    for (const auto& v : f.vertices()) indices.push_back(std::uint32_t(v.idx()));
  return as_chunk(out, std::move(indices));
}

struct Row {
  std::vector<double> triangles, psnr, ssim, holes, skins, ms;
  void add(double tris, const ImageMetrics& m, double milliseconds) {
    triangles.push_back(tris), psnr.push_back(m.psnr_db), ssim.push_back(m.ssim), holes.push_back(m.hole_fraction),
        skins.push_back(m.skin_fraction), ms.push_back(milliseconds);
  }
};

struct Args {
  std::string database, cells = "1";
  int views = 4, width = 320, height = 240;
  std::size_t decimater_max = 300000;
};

Args parse_args(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(s + " needs a value");
      return argv[++i];
    };
    if (s == "--cells") a.cells = value();
    else if (s == "--views") a.views = std::stoi(value());
    else if (s == "--size") std::tie(a.width, a.height) = parse_image_size(value());
    else if (s == "--decimater-max") a.decimater_max = std::stoull(value());
    else if (!s.empty() && s[0] != '-' && a.database.empty()) a.database = s;
    else throw std::invalid_argument("unknown argument " + s);
  }
  if (a.database.empty())
    throw std::invalid_argument(
        "usage: bench_baselines CELLS.db [--cells SEL] [--views N] [--size WxH] [--decimater-max TRIANGLES]");
  return a;
}

int run(int argc, char** argv) {
  const Args args = parse_args(argc, argv);
  if (!std::getenv("LP_NUM_THREADS")) setenv("LP_NUM_THREADS", "1", 1);
  CellDb db(args.database, CellDb::Mode::read_only);
  GeometryStore store(db.meta("store").value_or(""));
  const Vec3d up = up_axis(db.meta("up").value_or("z"));
  const auto regions = regions_of_config_text(db.meta("config").value_or(""));
  std::vector<CellSpec> specs;
  const CellIndex index(db);
  for (const auto& e : index.cells())
    if (e.done) specs.push_back({e.id, 0, e.gx, e.gy, e.gz, e.bounds});
  specs = select_cells(specs, args.cells);

  SceneDrawer drawer(std::shared_ptr<GlContext>(create_gl_context(GlBackend::osmesa, 1, 1)), store);
  ChunkRenderer lod_renderer(create_gl_context(GlBackend::osmesa, 1, 1));
  // Every baseline lit like the bake (its far field's images carry that light).
  const ShadingLights shading = shading_lights(shading_of_config_text(db.meta("config").value_or("")), up);
  drawer.set_shading(shading);
  lod_renderer.set_shading(shading);
  const auto loader = [&](std::int64_t id) { return store.load(id); };
  std::map<std::string, Row> rows;
  const char* order[] = {"truth", "impostor", "lod-meshopt", "lod-openmesh"};

  for (const auto& spec : specs) {
    const auto row = db.get_cell(spec.id, true);
    const DecodedCell cell = decode_cell(*row);
    const Box3d navigable = row->region >= 0 && row->region < int(regions.size())
                                ? navigable_part(row->bounds, regions[std::size_t(row->region)])
                                : row->bounds;
    // Same viewpoints as `cellbake verify --seed 1` (its random and reference views).
    const auto plans = plan_verify_views(row->bounds, navigable.empty() ? row->bounds : navigable, up, args.views,
                                         true, 1 * 0x9E3779B97F4A7C15ull + std::uint64_t(spec.id));

    auto t0 = std::chrono::steady_clock::now();
    const FarMesh far = far_field(store, cell.cull_box, row->bounds.center());
    const double far_s = seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    bool sloppy = false;
    const auto meshopt_lod = as_chunk(far, simplify_meshopt(far, row->far_triangles, sloppy));
    const double meshopt_s = seconds_since(t0);
    std::shared_ptr<const Chunk> openmesh_lod;
    std::size_t dropped = 0;
    double openmesh_s = 0;
    if (far.indices.size() / 3 <= args.decimater_max) {
      t0 = std::chrono::steady_clock::now();
      openmesh_lod = simplify_openmesh(far, row->far_triangles, dropped);
      openmesh_s = seconds_since(t0);
    }
    std::printf("cell %lld: far field %zu triangles (%.2f s to gather), budget %llu; meshopt -> %zu%s (%.2f s); ",
                (long long)spec.id, far.indices.size() / 3, far_s, (unsigned long long)row->far_triangles,
                meshopt_lod->triangle_count(), sloppy ? " sloppy" : "", meshopt_s);
    if (openmesh_lod)
      std::printf("openmesh -> %zu (%.2f s, %zu non-manifold faces dropped)\n", openmesh_lod->triangle_count(),
                  openmesh_s, dropped);
    else
      std::printf("openmesh skipped (far field > --decimater-max %zu)\n", args.decimater_max);

    for (const auto& plan : plans) {
      const RenderCamera camera = look_at_camera(plan.eye, plan.look, up, 60, args.width, args.height, 0.05);
      ViewFrame truth, impostor;
      drawer.draw_truth(camera, args.width, args.height, {}, truth);
      const SceneFrameStats ts = drawer.draw_truth(camera, args.width, args.height, {}, truth);
      drawer.draw_impostor(camera, args.width, args.height, cell, {}, impostor);
      const SceneFrameStats is = drawer.draw_impostor(camera, args.width, args.height, cell, {}, impostor);
      drawer.release_context();
      rows["truth"].add(double(ts.chunk_triangles), compare_frames(truth, truth), ts.milliseconds);
      rows["impostor"].add(double(cell.near_triangles + is.far_triangles), compare_frames(impostor, truth), is.milliseconds);

      auto draw_lod = [&](const char* name, const std::shared_ptr<const Chunk>& lod) {
        ViewFrame frame;
        frame.width = args.width;
        frame.height = args.height;
        double ms = 0;
        for (int pass = 0; pass < 2; ++pass) {  // the second, warm pass is timed
          const auto start = std::chrono::steady_clock::now();
          lod_renderer.begin_frame(args.width, args.height);
          lod_renderer.draw(camera, cell.cull_box, cell.near_ids, loader, BoxClip::keep_inside);
          const std::shared_ptr<const Chunk> chunks[] = {lod};
          lod_renderer.draw(camera, cell.cull_box, chunks, BoxClip::discard_inside);
          lod_renderer.read_frame(frame.color, frame.depth);
          ms = seconds_since(start) * 1000;
        }
        lod_renderer.clear_cache();  // the LOD chunk's id (-1) is reused by the next LOD
        lod_renderer.release_context();
        rows[name].add(double(cell.near_triangles + lod->triangle_count()), compare_frames(frame, truth), ms);
      };
      draw_lod("lod-meshopt", meshopt_lod);
      if (openmesh_lod) draw_lod("lod-openmesh", openmesh_lod);
    }
  }

  std::printf("\n%zu cells x %d views, %dx%d; medians over views (triangles: near field inside the cull box + far)\n",
              specs.size(), args.views, args.width, args.height);
  std::printf("%-14s %10s %9s %7s %8s %8s %9s\n", "method", "triangles", "PSNR dB", "SSIM", "holes", "skins", "ms");
  for (const char* name : order) {
    auto it = rows.find(name);
    if (it == rows.end()) continue;
    const Row& r = it->second;
    std::printf("%-14s %10.0f %9.2f %7.4f %8.4f %8.4f %9.2f\n", name, median_of(r.triangles), median_of(r.psnr),
                median_of(r.ssim), median_of(r.holes), median_of(r.skins), median_of(r.ms));
  }
  return 0;
}

}  // namespace
}  // namespace cellbake

int main(int argc, char** argv) {
  return cellbake::run_bench_program("bench_baselines", cellbake::run, argc, argv);
}
