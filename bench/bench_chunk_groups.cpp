// What merging neighbouring chunks buys the far field (stages/chunk_groups.h):
// for groups of --fanout^k consecutive chunks of a geometry store, the
// members' coarsest stored levels merged and simplified by build_chunk_lods
// (borders of the group locked), tier by tier (a tier merges the previous
// tier's coarsest groups). Prints per tier the triangles of the members'
// coarsest levels against each group level's, and the error those levels
// carry (the members' plus the group simplification's), with the distance
// at which far.lod_error_px allows that error (stages/chunk_lod.h), and the
// share of edges left open (one triangle: a border the simplifier locks)
// before and after merging.
//
//   bench_chunk_groups STORE.db [--fanout 8] [--tiers 3] [--error-px 1] [--face-size 512]
//
// Not a Google Benchmark program: it reads a store.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <vector>
#include <map>
#include <tuple>

#include "bench/bench_program.h"
#include "stages/chunk_groups.h"
#include "stages/chunk_lod.h"
#include "storage/geometry_store.h"

namespace cellbake {
namespace {

// Errors (metres) at which the tiers are compared: far.lod_error_px = 1 at
// 512-pixel faces allows them from 2.6, 10 and 41 m.
constexpr std::array<double, 3> kBudgets = {0.01, 0.04, 0.16};

struct Node {
  std::shared_ptr<const Chunk> mesh;  // its coarsest form
  double error = 0;                   // how far that lies from the model
  std::array<std::uint64_t, 3> within{};  // its fewest triangles within each of kBudgets
};

// Edges of `c` (corners at equal world positions taken as one, to a float)
// used by one triangle only, and all its edges.
std::pair<std::uint64_t, std::uint64_t> open_edges(const Chunk& c) {
  using Point = std::tuple<float, float, float>;
  std::map<std::pair<Point, Point>, int> uses;
  for (std::size_t t = 0; t < c.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) {
      const Vec3d a = c.world(c.indices[3 * t + std::size_t(k)]), b = c.world(c.indices[3 * t + std::size_t((k + 1) % 3)]);
      Point pa{float(a.x), float(a.y), float(a.z)}, pb{float(b.x), float(b.y), float(b.z)};
      if (pb < pa) std::swap(pa, pb);
      ++uses[{pa, pb}];
    }
  std::uint64_t open = 0;
  for (const auto& [edge, n] : uses) open += n == 1;
  return {open, uses.size()};
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, std::size_t(q * double(v.size())))];
}

int run(int argc, char** argv) {
  CLI::App app("Triangles and error of merged chunk groups");
  std::string store_path;
  int fanout = 8, tiers = 3, face_size = 512;
  double error_px = 1.0;
  app.add_option("store", store_path, "Geometry store")->required();
  app.add_option("--fanout", fanout, "Members per group")->check(CLI::Range(2, 64));
  app.add_option("--tiers", tiers, "Tiers of groups")->check(CLI::Range(1, 8));
  app.add_option("--error-px", error_px, "far.lod_error_px");
  app.add_option("--face-size", face_size, "sample.face_size");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  const GeometryStore store(store_path);
  std::vector<Node> nodes;
  std::uint64_t full = 0;
  for (const ChunkRef& r : store.query(store.model_bounds())) {
    const std::vector<ChunkLodRef> levels = store.lods(r.id);
    full += r.triangle_count;
    Node n;
    if (levels.empty()) {
      n.mesh = store.load(r.id);
    } else {
      n.mesh = store.load_lod(r.id, levels.back().level);
      n.error = levels.back().error;
    }
    for (std::size_t k = 0; k < kBudgets.size(); ++k) {
      n.within[k] = r.triangle_count;
      for (const ChunkLodRef& l : levels)
        if (l.error <= kBudgets[k]) n.within[k] = std::min<std::uint64_t>(n.within[k], l.triangle_count);
    }
    nodes.push_back(std::move(n));
  }
  const auto triangles = [](const std::vector<Node>& v) {
    std::uint64_t t = 0;
    for (const Node& n : v) t += n.mesh->triangle_count();
    return t;
  };
  std::printf("chunks %zu: %llu triangles, %llu at their coarsest levels\n", nodes.size(),
              (unsigned long long)full, (unsigned long long)triangles(nodes));
  const auto print_within = [&](const char* what, const std::vector<Node>& v) {
    std::printf("%s within", what);
    for (std::size_t k = 0; k < kBudgets.size(); ++k) {
      std::uint64_t t = 0;
      for (const Node& n : v) t += n.within[k];
      std::printf(" %.2f m: %llu%s", kBudgets[k], (unsigned long long)t, k + 1 < kBudgets.size() ? "," : "\n");
    }
  };
  print_within("chunks", nodes);
  const double per_metre = error_px * 2.0 / face_size;  // allowed error per metre of distance
  for (int tier = 1; tier <= tiers && nodes.size() > 1; ++tier) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<Node> next;
    std::vector<double> errors;
    std::uint64_t merged_triangles = 0, member_edges = 0, member_open = 0, merged_edges = 0, merged_open = 0;
    for (std::size_t first = 0; first < nodes.size(); first += std::size_t(fanout)) {
      std::vector<const Chunk*> members;
      double member_error = 0;
      for (std::size_t k = first; k < std::min(nodes.size(), first + std::size_t(fanout)); ++k) {
        members.push_back(nodes[k].mesh.get());
        member_error = std::max(member_error, nodes[k].error);
      }
      const Chunk merged = merge_chunks(members, std::int64_t(next.size() + 1));
      merged_triangles += merged.triangle_count();
      for (const Chunk* m : members) {
        const auto [open, all] = open_edges(*m);
        member_open += open, member_edges += all;
      }
      const auto [open, all] = open_edges(merged);
      merged_open += open, merged_edges += all;
      ChunkLodParams params;
      params.max_levels = 12;
      std::vector<ChunkLod> levels = build_chunk_lods(merged, params);
      // Within each budget: the group's coarsest level that keeps to it, or
      // its members as they best keep to it on their own.
      std::array<std::uint64_t, 3> group_within{};
      for (std::size_t k = 0; k < kBudgets.size(); ++k) {
        for (std::size_t m = first; m < std::min(nodes.size(), first + std::size_t(fanout)); ++m)
          group_within[k] += nodes[m].within[k];
        for (const ChunkLod& l : levels)
          if (member_error + l.ref.error <= kBudgets[k])
            group_within[k] = std::min<std::uint64_t>(group_within[k], l.ref.triangle_count);
      }
      Node n;
      if (levels.empty()) {
        n.mesh = std::make_shared<Chunk>(merged);
        n.error = member_error;
      } else {
        n.error = member_error + levels.back().ref.error;
        n.mesh = std::make_shared<Chunk>(std::move(levels.back().chunk));
      }
      errors.push_back(n.error);
      n.within = group_within;
      next.push_back(std::move(n));
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("tier %d: open edges %.1f %% of the members' (each alone), %.1f %% merged\n", tier,
                100.0 * double(member_open) / double(std::max<std::uint64_t>(1, member_edges)),
                100.0 * double(merged_open) / double(std::max<std::uint64_t>(1, merged_edges)));
    std::printf("tier %d: %zu groups of %d; members %llu triangles -> %llu (%.2fx); error median %.4f m (allowed "
                "from %.1f m), p90 %.4f m (%.1f m); %.1f s\n",
                tier, next.size(), fanout, (unsigned long long)merged_triangles,
                (unsigned long long)triangles(next), double(merged_triangles) / double(std::max<std::uint64_t>(1, triangles(next))),
                percentile(errors, 0.5), percentile(errors, 0.5) / per_metre, percentile(errors, 0.9),
                percentile(errors, 0.9) / per_metre, seconds);
    nodes = std::move(next);
    print_within("  groups", nodes);
  }
  return 0;
}

}  // namespace
}  // namespace cellbake

int main(int argc, char** argv) {
  return cellbake::run_bench_program("bench_chunk_groups", cellbake::run, argc, argv);
}
