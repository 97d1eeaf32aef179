#include "runner/ingest_summary.h"

#include <cstdio>
#include <memory>

#include <nlohmann/json.hpp>

#include "runner/console.h"
#include "runner/progress.h"

namespace cellbake {

ProgressCallback ingest_progress() {
  if (quiet_output()) return {};
  auto last_phase = std::make_shared<std::string>();
  auto bar = std::make_shared<std::unique_ptr<ProgressBar>>();
  return [last_phase, bar](const std::string& phase, std::uint64_t done, std::uint64_t total) {
    if (phase != *last_phase) {
      if (*bar) (*bar)->finish();
      *last_phase = phase;
      bar->reset();
      if (phase == "done") return;
      *bar = std::make_unique<ProgressBar>("ingest " + phase, total, phase == "write" ? "chunks" : "triangles");
    }
    (*bar)->update(done);
  };
}

void print_ingest_summary(const IngestReport& r, const std::string& store, bool json) {
  const double total = r.read_seconds + r.chunk_seconds + r.write_seconds;
  if (json) {
    nlohmann::json warnings = nlohmann::json::array();
    for (const std::string& w : r.texture_warnings) warnings.push_back(w);
    for (const std::string& w : r.input_warnings) warnings.push_back(w);
    if (!r.up_warning.empty()) warnings.push_back(r.up_warning);
    const nlohmann::json j{
        {"store", store},
        {"triangles_read", r.triangles_read},
        {"triangles_stored", r.triangles_stored},
        {"polygons_triangulated", r.polygons_triangulated},
        {"skipped_degenerate", r.skipped_degenerate},
        {"skipped_duplicate", r.skipped_duplicate},
        {"chunks", r.chunks},
        {"chunk_lods", r.chunk_lods},
        {"lod_triangles", r.lod_triangles},
        {"vertices", r.vertices},
        {"bounds",
         {{"min", {r.bounds.lo.x, r.bounds.lo.y, r.bounds.lo.z}}, {"max", {r.bounds.hi.x, r.bounds.hi.y, r.bounds.hi.z}}}},
        {"seconds", {{"read", r.read_seconds}, {"chunk", r.chunk_seconds}, {"write", r.write_seconds}, {"total", total}}},
        {"up", r.up.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.up)},
        {"up_source", r.up_source},
        {"up_from_geometry",
         {{"axis", r.up_from_geometry.axis.empty() ? nlohmann::json(nullptr) : nlohmann::json(r.up_from_geometry.axis)},
          {"evidence", r.up_from_geometry.evidence}}},
        {"textures", r.textures},
        {"texture_bytes", r.texture_bytes},
        {"warnings", warnings},
        {"vertex_colour_notes", r.vertex_colour_notes},
        {"content_hash", r.content_hash}};
    std::printf("%s\n", j.dump(2).c_str());
    return;
  }
  std::printf("ingested %llu triangles into %s\n", (unsigned long long)r.triangles_stored, store.c_str());
  std::printf("  read %llu triangles (%llu polygons triangulated)\n", (unsigned long long)r.triangles_read,
              (unsigned long long)r.polygons_triangulated);
  std::printf("  skipped %llu degenerate (zero-area) and %llu duplicate triangles\n",
              (unsigned long long)r.skipped_degenerate, (unsigned long long)r.skipped_duplicate);
  std::printf("  %llu chunks, %llu vertices, bounds (%.3f %.3f %.3f)-(%.3f %.3f %.3f)\n", (unsigned long long)r.chunks,
              (unsigned long long)r.vertices, r.bounds.lo.x, r.bounds.lo.y, r.bounds.lo.z, r.bounds.hi.x,
              r.bounds.hi.y, r.bounds.hi.z);
  if (r.chunk_lods > 0)
    std::printf("  %llu simplified chunk levels for the far field (%llu triangles, all levels together)\n",
                (unsigned long long)r.chunk_lods, (unsigned long long)r.lod_triangles);
  std::printf("  time: read %.2f s, chunk %.2f s, write %.2f s, total %.2f s (%.2f M triangles/s)\n", r.read_seconds,
              r.chunk_seconds, r.write_seconds, total, total > 0 ? r.triangles_read / total / 1e6 : 0.0);
  if (!r.up.empty())
    std::printf("  up axis: %s (%s), recorded in the store\n", r.up.c_str(), r.up_source.c_str());
  else
    std::printf("  up axis: not recorded: %s; bake assumes z (ingest --up y|z records one)\n", r.up_source.c_str());
  if (!r.up_warning.empty()) std::printf("  %s\n", r.up_warning.c_str());
  for (const std::string& note : r.vertex_colour_notes) std::printf("  %s\n", note.c_str());
  if (r.textures > 0)
    std::printf("  %llu textures stored (%.1f MB decoded)\n", (unsigned long long)r.textures, r.texture_bytes / 1e6);
  if (!r.texture_warnings.empty()) {
    std::printf("  warning: %zu texture(s) could not be used:\n", r.texture_warnings.size());
    for (const std::string& w : r.texture_warnings) std::printf("    %s\n", w.c_str());
  }
  if (!r.input_warnings.empty()) {
    std::printf("  warning: %zu thing(s) in the model files skipped or read leniently:\n",
                r.input_warnings.size());
    for (const std::string& w : r.input_warnings) std::printf("    %s\n", w.c_str());
  }
  std::printf("  content hash %s\n", r.content_hash.c_str());
}

}  // namespace cellbake
