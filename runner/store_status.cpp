#include "runner/store_status.h"

#include <algorithm>

#include "runner/number_text.h"

namespace cellbake {

nlohmann::json store_status_json(const GeometryStore& store) {
  const StoreSummary& s = store.summary();
  const Box3d& b = s.bounds;
  nlohmann::json j;
  j["kind"] = "geometry_store";
  j["path"] = store.path().string();
  if (s.triangles > 0) {
    j["bounds"] = {{"min", {b.lo.x, b.lo.y, b.lo.z}}, {"max", {b.hi.x, b.hi.y, b.hi.z}}};
    j["size"] = {b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z};
  } else {
    j["bounds"] = nullptr;
    j["size"] = nullptr;
  }
  j["triangles"] = s.triangles;
  j["vertices"] = s.vertices;
  j["chunks"] = s.chunks;
  // Index 0 is the default material every table starts with.
  const std::size_t materials = store.materials().size();
  j["materials"] = materials > 0 ? materials - 1 : 0;
  j["textures"] = store.texture_count();
  j["units"] = s.units;
  j["up"] = s.up.empty() ? nlohmann::json(nullptr) : nlohmann::json(s.up);
  j["up_source"] = s.up_source;
  j["content_hash"] = s.content_hash;
  nlohmann::json sources = nlohmann::json::array();
  for (const auto& src : store.sources())
    sources.push_back({{"path", src.path}, {"bytes", src.bytes}, {"triangles", src.triangles}});
  j["sources"] = sources;
  return j;
}

void print_store_status(const GeometryStore& store, std::FILE* out) {
  std::fprintf(out, "%s: geometry store (not baked; `cellbake bake --store %s ...` bakes it)\n",
               store.path().c_str(), store.path().c_str());
  print_store_facts(store, out);
}

void print_store_facts(const GeometryStore& store, std::FILE* out) {
  const StoreSummary& s = store.summary();
  const Box3d& b = s.bounds;
  const nlohmann::json j = store_status_json(store);
  if (s.triangles > 0) {
    // Six significant digits of the model's size, whatever its distance from the origin.
    const double step = six_digit_step(std::max({b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z}));
    const auto t = [&](double v) { return decimal_text(v, step); };
    std::fprintf(out, "bounds: (%s, %s, %s) .. (%s, %s, %s) %s\n", t(b.lo.x).c_str(), t(b.lo.y).c_str(),
                 t(b.lo.z).c_str(), t(b.hi.x).c_str(), t(b.hi.y).c_str(), t(b.hi.z).c_str(), s.units.c_str());
    std::fprintf(out, "size: %.6g x %.6g x %.6g %s\n", b.hi.x - b.lo.x, b.hi.y - b.lo.y, b.hi.z - b.lo.z,
                 s.units.c_str());
  } else {
    std::fprintf(out, "bounds: empty (no triangles)\n");
  }
  std::fprintf(out, "triangles: %llu, vertices: %llu, chunks: %llu\n", (unsigned long long)s.triangles,
               (unsigned long long)s.vertices, (unsigned long long)s.chunks);
  std::fprintf(out, "materials: %llu, textures: %llu\n", (unsigned long long)j["materials"].get<std::uint64_t>(),
               (unsigned long long)j["textures"].get<std::uint64_t>());
  if (s.up.empty())
    std::fprintf(out, "up axis: not recorded (bake assumes z; `--up y` or `ingest --up` to change)\n");
  else
    std::fprintf(out, "up axis: %s (%s)\n", s.up.c_str(), s.up_source.empty() ? "recorded at ingest" : s.up_source.c_str());
  std::fprintf(out, "content hash: %s\n", s.content_hash.c_str());
  for (const auto& src : j["sources"])
    std::fprintf(out, "source: %s (%llu bytes, %llu triangles)\n", src["path"].get<std::string>().c_str(),
                 (unsigned long long)src["bytes"].get<std::uint64_t>(),
                 (unsigned long long)src["triangles"].get<std::uint64_t>());
}

}  // namespace cellbake
