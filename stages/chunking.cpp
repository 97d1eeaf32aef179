#include "stages/chunking.h"

#include "stages/normal_packing.h"

#include <xxhash.h>

#include <algorithm>
#include <cstring>
#include <unordered_map>

namespace cellbake {
namespace {

bool same_key(const TriangleKey& a, const TriangleKey& b) {
  return a.centroid == b.centroid && a.shape_hash == b.shape_hash;
}

bool lex_less(const Vec3d& a, const Vec3d& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
}

void split(std::vector<TriangleKey>& keys, std::size_t begin, std::size_t end, std::size_t max_triangles,
           std::vector<ChunkRange>& out) {
  const std::size_t n = end - begin;
  if (n <= max_triangles) {
    std::sort(keys.begin() + begin, keys.begin() + end,
              [](const TriangleKey& a, const TriangleKey& b) { return a.index < b.index; });
    out.push_back({begin, end});
    return;
  }
  Box3d cb;
  for (std::size_t i = begin; i < end; ++i) cb.expand(keys[i].centroid);
  const Vec3d ext = cb.extent();
  // Longest axis; near-ties (relative 1e-6) go to the lower axis so that a
  // translated copy of a model, whose extents differ by rounding, splits alike.
  int axis = 0;
  for (int a = 1; a < 3; ++a)
    if (ext[a] > ext[axis] * (1 + 1e-6)) axis = a;
  auto less = [axis](const TriangleKey& a, const TriangleKey& b) {
    if (a.centroid[axis] != b.centroid[axis]) return a.centroid[axis] < b.centroid[axis];
    if (a.centroid != b.centroid) return lex_less(a.centroid, b.centroid);
    if (a.shape_hash != b.shape_hash) return a.shape_hash < b.shape_hash;
    return a.index < b.index;
  };
  auto first = keys.begin() + begin, last = keys.begin() + end;
  auto mid = first + n / 2;
  std::nth_element(first, mid, last, less);
  // Keep exact duplicates together: move copies of the pivot from the left side to the right side.
  const TriangleKey pivot = *mid;
  auto left_end = std::partition(first, mid, [&](const TriangleKey& k) { return !same_key(k, pivot); });
  auto cut = mid;
  if (left_end != mid) {
    if (left_end != first) {
      cut = left_end;
    } else {
      cut = std::partition(mid, last, [&](const TriangleKey& k) { return same_key(k, pivot); });
    }
  }
  if (cut == first || cut == last) {  // one run of identical triangles
    std::sort(first, last, [](const TriangleKey& a, const TriangleKey& b) { return a.index < b.index; });
    out.push_back({begin, end});
    return;
  }
  const std::size_t c = static_cast<std::size_t>(cut - keys.begin());
  split(keys, begin, c, max_triangles, out);
  split(keys, c, end, max_triangles, out);
}

struct VertexKey {
  double x, y, z;
  Rgba8 c;
  Uv uv;
  Vec3f n;
  bool operator==(const VertexKey& o) const {
    return std::memcmp(&x, &o.x, 24) == 0 && c == o.c && uv == o.uv && n == o.n;
  }
};
struct VertexKeyHash {
  std::size_t operator()(const VertexKey& k) const {
    unsigned char buf[24 + 4 + 8 + 12];
    std::memcpy(buf, &k.x, 24);
    std::memcpy(buf + 24, &k.c, 4);
    std::memcpy(buf + 28, &k.uv, 8);
    std::memcpy(buf + 36, &k.n, 12);
    return static_cast<std::size_t>(XXH3_64bits(buf, sizeof buf));
  }
};

// The unit normal of corner `c` as stored: the source's normal when it gave a
// usable one, else the face normal; quantised as the store keeps it.
Vec3f corner_normal(const Triangle& t, int c) {
  if (t.has_normals) {
    const Vec3f& n = t.normal[c];
    const float len2 = n.x * n.x + n.y * n.y + n.z * n.z;
    if (len2 > 1e-12f && std::isfinite(len2)) return quantise_normal(n);
  }
  const Vec3d f = cross(t.p[1] - t.p[0], t.p[2] - t.p[0]);
  return quantise_normal({static_cast<float>(f.x), static_cast<float>(f.y), static_cast<float>(f.z)});
}

}  // namespace

std::vector<ChunkRange> split_into_chunks(std::vector<TriangleKey>& keys, std::size_t max_triangles) {
  std::vector<ChunkRange> out;
  if (keys.empty()) return out;
  split(keys, 0, keys.size(), std::max<std::size_t>(1, max_triangles), out);
  return out;
}

TriangleKey make_triangle_key(const Triangle& t, std::uint32_t index) {
  std::array<Vec3d, 3> p = t.p;
  std::sort(p.begin(), p.end(), lex_less);
  TriangleKey k;
  // Sum in canonical order so the centroid does not depend on corner order.
  k.centroid = (p[0] + p[1] + p[2]) * (1.0 / 3.0);
  k.shape_hash = XXH3_64bits(p.data(), sizeof p);
  k.index = index;
  return k;
}

bool is_degenerate(const Triangle& t) {
  const Vec3d e0 = t.p[1] - t.p[0], e1 = t.p[2] - t.p[0], e2 = t.p[2] - t.p[1];
  const double longest2 = std::max({dot(e0, e0), dot(e1, e1), dot(e2, e2)});
  if (longest2 == 0) return true;
  const double area2 = length(cross(e0, e1));
  return area2 <= 1e-12 * longest2;
}

bool same_corners(const Triangle& a, const Triangle& b) {
  std::array<Vec3d, 3> pa = a.p, pb = b.p;
  std::sort(pa.begin(), pa.end(), lex_less);
  std::sort(pb.begin(), pb.end(), lex_less);
  return pa == pb;
}

Chunk build_chunk(const std::vector<const Triangle*>& triangles) {
  Chunk chunk;
  for (const Triangle* t : triangles)
    for (const Vec3d& p : t->p) chunk.bounds.expand(p);
  chunk.origin = chunk.bounds.center();
  bool any_uv = false, any_material = false, any_normal = false;
  for (const Triangle* t : triangles) {
    any_material |= t->material != 0;
    any_normal |= t->has_normals;
    for (const Uv& uv : t->uv) any_uv |= (uv.u != 0 || uv.v != 0);
  }
  std::unordered_map<VertexKey, std::uint32_t, VertexKeyHash> index_of;
  index_of.reserve(triangles.size() * 2);
  chunk.indices.reserve(triangles.size() * 3);
  for (const Triangle* t : triangles) {
    for (int c = 0; c < 3; ++c) {
      const Vec3f normal = any_normal ? corner_normal(*t, c) : Vec3f{};
      VertexKey key{t->p[c].x, t->p[c].y, t->p[c].z, t->color[c], any_uv ? t->uv[c] : Uv{}, normal};
      auto [it, inserted] = index_of.try_emplace(key, static_cast<std::uint32_t>(chunk.positions.size()));
      if (inserted) {
        const Vec3d local = t->p[c] - chunk.origin;
        chunk.positions.push_back({static_cast<float>(local.x), static_cast<float>(local.y),
                                   static_cast<float>(local.z)});
        chunk.colors.push_back(t->color[c]);
        if (any_uv) chunk.uvs.push_back(t->uv[c]);
        if (any_normal) chunk.normals.push_back(normal);
      }
      chunk.indices.push_back(it->second);
    }
    if (any_material) chunk.materials.push_back(t->material);
  }
  return chunk;
}

}  // namespace cellbake
