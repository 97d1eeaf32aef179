// Face-mesh codecs on real baked faces: reads every face mesh of the selected
// cells of a cell database, puts its vertices back on their pixel rays (as the
// viewer does after the version-1 quantisation), then encodes it with
//  * v1   - per-axis quantisation over the mesh bounds + meshoptimizer codecs;
//  * grid - blob version 2 (pixel corners, log depth, predicted residuals, zstd)
//           at each --depth-error and --zstd-level (the first level is used for
//           every depth error, every level for the first depth error);
// and prints bytes per triangle, the largest relative depth error and the
// largest pixel-corner error the round trip made, and decode milliseconds per face.
//
//   bench_mesh_codec /tmp/demo/c3.db [--cells FIRST-LAST] [--depth-error 0.001,0.0005] [--zstd-level 15,19]
//                    [--repeat 5]
//
// Not a Google Benchmark program: it reads a database and reports error
// figures next to the sizes and times.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "stages/encode/encode.h"
#include "storage/cell_db.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

struct Args {
  std::string db, cells;
  std::vector<double> depth_errors = {0.002, 0.001, 0.0005};
  std::vector<int> zstd_levels = {MeshEncodeParams{}.zstd_level};
  int repeat = 5;
};

Args parse_args(int argc, char** argv) {
  Args a;
  CLI::App app{"Face-mesh codecs: bytes per triangle, depth error and decode time on stored faces", "bench_mesh_codec"};
  app.add_option("database", a.db, "Cell database")->required();
  app.add_option("--cells", a.cells, "Cells FIRST-LAST (default: all)");
  app.add_option("--depth-error", a.depth_errors, "Relative depth errors to code at")->delimiter(',')->capture_default_str();
  app.add_option("--zstd-level", a.zstd_levels, "zstd levels of the grid coding (the first one for every depth error)")
      ->delimiter(',')
      ->check(CLI::Range(1, 22))
      ->capture_default_str();
  app.add_option("--repeat", a.repeat, "Timed repetitions")->check(CLI::PositiveNumber)->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::exit(app.exit(e));
  }
  return a;
}

int face_size_of(const CellDb& db) {
  const std::string config = db.meta("config").value_or("");
  const std::string key = "sample.face_size=";
  const std::size_t at = config.find(key);
  return at == std::string::npos ? 512 : std::stoi(config.substr(at + key.size()));
}

// The mesh with every vertex moved onto the ray through its pixel corner at
// its planar depth (undoing version 1's off-ray quantisation).
FaceMesh on_rays(const FaceMesh& m, int face, int n) {
  FaceMesh out = m;
  const FaceBasis b = cube_face_basis(face);
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    const double i = std::nearbyint(m.uvs[v].u * n), j = std::nearbyint(m.uvs[v].v * n);
    const Vec3f& p = m.positions[v];
    const double z = b.forward.x * p.x + b.forward.y * p.y + b.forward.z * p.z;
    const Vec3d d = cube_face_direction(b, 2 * i / n - 1, 1 - 2 * j / n);
    out.positions[v] = {float(d.x * z), float(d.y * z), float(d.z * z)};
    out.uvs[v] = {float(i / n), float(j / n)};
  }
  return out;
}

double decode_ms(const std::vector<std::uint8_t>& blob, int repeat) {
  const auto t0 = Clock::now();
  std::size_t sink = 0;
  for (int r = 0; r < repeat; ++r) sink += decode_face_mesh(blob).positions.size();
  if (sink == 1) std::printf(" ");
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count() / repeat;
}

struct Totals {
  double bytes = 0, encode_ms = 0, decode_ms = 0, max_depth_error = 0, max_corner_error = 0;
  std::size_t fallbacks = 0;
};

// Largest relative planar-depth error and pixel-corner error between a mesh
// and its decoded copy, matched by (corner, depth) after sorting.
void measure(const FaceMesh& in, const FaceMesh& out, int face, int n, Totals& t) {
  const FaceBasis b = cube_face_basis(face);
  auto keys = [&](const FaceMesh& m) {
    std::vector<std::array<double, 3>> k(m.positions.size());
    for (std::size_t v = 0; v < k.size(); ++v) {
      const Vec3f& p = m.positions[v];
      k[v] = {double(m.uvs[v].u) * n, double(m.uvs[v].v) * n, b.forward.x * p.x + b.forward.y * p.y + b.forward.z * p.z};
    }
    std::sort(k.begin(), k.end());
    return k;
  };
  const auto a = keys(in), c = keys(out);
  if (a.size() != c.size()) {
    t.max_depth_error = INFINITY;
    return;
  }
  for (std::size_t v = 0; v < a.size(); ++v) {
    t.max_corner_error = std::max({t.max_corner_error, std::fabs(a[v][0] - c[v][0]), std::fabs(a[v][1] - c[v][1])});
    t.max_depth_error = std::max(t.max_depth_error, std::fabs(c[v][2] - a[v][2]) / a[v][2]);
  }
}

int run(const Args& args) {
  const CellDb db(args.db, CellDb::Mode::read_only);
  const int n = face_size_of(db);
  std::vector<std::int64_t> ids = db.cell_ids();
  if (!args.cells.empty()) {
    const std::size_t dash = args.cells.find('-');
    const std::int64_t lo = std::stoll(args.cells.substr(0, dash));
    const std::int64_t hi = dash == std::string::npos ? lo : std::stoll(args.cells.substr(dash + 1));
    std::vector<std::int64_t> kept;
    for (std::int64_t id : ids)
      if (id >= lo && id <= hi) kept.push_back(id);
    ids = kept;
  }
  std::size_t faces = 0, triangles = 0;
  Totals stored, v1;
  // Grid codings measured: every depth error at the first level, then the
  // other levels at the first depth error.
  struct Variant {
    double depth_error;
    int zstd_level;
  };
  std::vector<Variant> variants;
  for (double e : args.depth_errors) variants.push_back({e, args.zstd_levels.front()});
  for (std::size_t l = 1; l < args.zstd_levels.size(); ++l)
    variants.push_back({args.depth_errors.front(), args.zstd_levels[l]});
  std::vector<Totals> grid(variants.size());
  for (std::int64_t id : ids) {
    const std::optional<CellRow> row = db.get_cell(id);
    if (!row) continue;
    for (const SampleRow& s : row->samples)
      for (const FaceRow& f : s.faces) {
        const FaceMesh mesh = on_rays(decode_face_mesh(f.mesh), f.face, n);
        if (mesh.indices.empty()) continue;
        ++faces;
        triangles += mesh.triangle_count();
        stored.bytes += double(f.mesh.size());
        MeshEncodeParams p1;
        const auto b1 = encode_face_mesh(mesh, p1);
        v1.bytes += double(b1.size());
        v1.decode_ms += decode_ms(b1, args.repeat);
        for (std::size_t e = 0; e < variants.size(); ++e) {
          MeshEncodeParams p2;
          p2.face = f.face;
          p2.face_size = n;
          p2.depth_error_relative = variants[e].depth_error;
          p2.zstd_level = variants[e].zstd_level;
          const auto t0 = Clock::now();
          const auto b2 = encode_face_mesh(mesh, p2);
          grid[e].encode_ms += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
          if (b2[4] != 2) ++grid[e].fallbacks;
          grid[e].bytes += double(b2.size());
          grid[e].decode_ms += decode_ms(b2, args.repeat);
          measure(mesh, decode_face_mesh(b2), f.face, n, grid[e]);
        }
      }
  }
  if (faces == 0) throw std::runtime_error("no non-empty faces in the selected cells");
  std::printf("%zu cells, %zu non-empty faces, %zu triangles (%.0f per face), face size %d\n", ids.size(), faces,
              triangles, double(triangles) / faces, n);
  std::printf("%-22s %10s %12s %14s %14s %10s %10s\n", "codec", "B/triangle", "KB/face", "depth err rel",
              "corner err px", "decode ms", "encode ms");
  std::printf("%-22s %10.2f %12.1f %14s %14s %10s\n", "stored (as baked)", stored.bytes / triangles,
              stored.bytes / faces / 1024, "-", "-", "-");
  std::printf("%-22s %10.2f %12.1f %14s %14s %10.3f\n", "v1 16-bit", v1.bytes / triangles, v1.bytes / faces / 1024,
              "-", "-", v1.decode_ms / faces);
  for (std::size_t e = 0; e < grid.size(); ++e) {
    char name[64];
    std::snprintf(name, sizeof name, "grid e=%g zstd %d", variants[e].depth_error, variants[e].zstd_level);
    std::printf("%-22s %10.2f %12.1f %14.6f %14.6f %10.3f %10.2f%s\n", name, grid[e].bytes / triangles,
                grid[e].bytes / faces / 1024, grid[e].max_depth_error, grid[e].max_corner_error,
                grid[e].decode_ms / faces, grid[e].encode_ms / faces, grid[e].fallbacks ? " (fallbacks!)" : "");
  }
  return 0;
}

}  // namespace
}  // namespace cellbake

int main(int argc, char** argv) {
  try {
    return cellbake::run(cellbake::parse_args(argc, argv));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_mesh_codec: %s\n", e.what());
    return 1;
  }
}
