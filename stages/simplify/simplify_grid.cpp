// Pixel-grid view of a dense depth mesh (see simplify_grid.h).
#include "stages/simplify/simplify_grid.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace cellbake {

double inverse_planar_depth(Vec3f p, double lattice_x, double lattice_y, int size) {
  const double s = 2.0 * lattice_x / size - 1.0, t = 1.0 - 2.0 * lattice_y / size;
  const double r = std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z);
  return std::sqrt(1.0 + s * s + t * t) / r;
}

FaceGrid read_face_grid(const FaceMesh& mesh, int face_size) {
  const int n = face_size;
  if (n <= 0) throw std::invalid_argument("simplify: face size " + std::to_string(n) + " is not positive");
  if (mesh.uvs.size() != mesh.positions.size())
    throw std::invalid_argument("simplify: mesh has " + std::to_string(mesh.positions.size()) + " positions but " +
                                std::to_string(mesh.uvs.size()) + " uvs");
  if (mesh.indices.size() % 3 != 0) throw std::invalid_argument("simplify: index count is not a multiple of 3");
  FaceGrid g;
  g.size = n;
  const std::size_t nv = mesh.positions.size();
  g.x.resize(nv);
  g.y.resize(nv);
  g.w.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    const double fx = double(mesh.uvs[v].u) * n, fy = double(mesh.uvs[v].v) * n;
    const double rx = std::round(fx), ry = std::round(fy);
    if (!(std::abs(fx - rx) < 1e-3 && std::abs(fy - ry) < 1e-3 && rx >= 0 && ry >= 0 && rx <= n && ry <= n))
      throw std::invalid_argument("simplify: vertex " + std::to_string(v) + " uv is not a pixel corner of a " +
                                  std::to_string(n) + "^2 face");
    g.x[v] = std::int32_t(rx);
    g.y[v] = std::int32_t(ry);
    g.w[v] = inverse_planar_depth(mesh.positions[v], rx, ry, n);
    if (!(std::isfinite(g.w[v]) && g.w[v] > 0))
      throw std::invalid_argument("simplify: vertex " + std::to_string(v) + " has no positive finite depth");
  }
  g.corner_vertex.assign(std::size_t(n) * n, {kNoVertex, kNoVertex, kNoVertex, kNoVertex});
  std::vector<std::uint8_t> pixel_triangles(std::size_t(n) * n, 0);  // per pixel: triangles read so far
  const std::size_t nt = mesh.indices.size() / 3;
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t* tri = &mesh.indices[3 * t];
    for (int k = 0; k < 3; ++k)
      if (tri[k] >= nv) throw std::invalid_argument("simplify: triangle " + std::to_string(t) + " index out of range");
    const int i = std::min({g.x[tri[0]], g.x[tri[1]], g.x[tri[2]]});
    const int j = std::min({g.y[tri[0]], g.y[tri[1]], g.y[tri[2]]});
    const long orient = long(g.x[tri[1]] - g.x[tri[0]]) * (g.y[tri[2]] - g.y[tri[0]]) -
                        long(g.y[tri[1]] - g.y[tri[0]]) * (g.x[tri[2]] - g.x[tri[0]]);
    bool ok = i < n && j < n && orient != 0;
    if (t == 0) g.orientation = orient > 0 ? 1 : -1;
    ok = ok && (orient > 0 ? 1 : -1) == g.orientation;
    auto& slots = g.corner_vertex[std::size_t(j) * n + i];
    for (int k = 0; k < 3 && ok; ++k) {
      const int dx = g.x[tri[k]] - i, dy = g.y[tri[k]] - j;
      if (dx > 1 || dy > 1) {
        ok = false;
        break;
      }
      std::uint32_t& slot = slots[dy * 2 + dx];
      if (slot != kNoVertex && slot != tri[k]) ok = false;
      slot = tri[k];
    }
    if (ok) ok = ++pixel_triangles[std::size_t(j) * n + i] <= 2;
    if (!ok)
      throw std::invalid_argument("simplify: triangle " + std::to_string(t) +
                                  " is not half of a pixel of a grid mesh (two consistently oriented triangles per pixel)");
  }
  for (std::size_t p = 0; p < g.corner_vertex.size(); ++p) {
    const auto& c = g.corner_vertex[p];
    const bool any = c[0] != kNoVertex || c[1] != kNoVertex || c[2] != kNoVertex || c[3] != kNoVertex;
    const bool all = c[0] != kNoVertex && c[1] != kNoVertex && c[2] != kNoVertex && c[3] != kNoVertex;
    if (any && (!all || pixel_triangles[p] != 2))
      throw std::invalid_argument("simplify: pixel (" + std::to_string(p % n) + ", " + std::to_string(p / n) +
                                  ") is not covered by exactly two triangles on its four corners");
  }
  return g;
}

}  // namespace cellbake
