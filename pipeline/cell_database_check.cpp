#include "pipeline/cell_database_check.h"

#include <cmath>
#include <mutex>

#include "pipeline/bake_config.h"
#include "pipeline/cell_grid.h"
#include "pipeline/cell_job.h"
#include "pipeline/level_chunk_source.h"
#include "pipeline/sample_backend.h"
#include "stages/raycast/chunk_bvh_cache.h"
#include "storage/meta_values.h"

namespace cellbake {
namespace {

// A store's content hash as a bake records it: a word of printable ASCII
// (32 hex digits from ingest; test stores name theirs), nothing a reader or a
// printed command could trip over.
bool is_store_hash(const std::string& s) {
  if (s.empty() || s.size() > 128) return false;
  for (char c : s)
    if (c <= ' ' || c > '~') return false;
  return true;
}

// The model as cells baked with `config` from `store` sampled it, for
// check_face_images_against_model: the bake's discard box, shading and near
// plane, one ray per pixel, with Embree (a few thousand rays a face: no GPU
// context is worth probing for, and probing EGL under the state's lock upset
// TSan). A model whose BVH fits one batch of the bake's Embree cap is traced
// whole by one sampler for every cell; a larger one, per cell, as its stored
// levels within a pixel of the resampled face (LevelChunkSource), so the
// check costs about as much at 82 M triangles as at 12.7 M. The sampler
// starts on first use; calls are serialised.
FarFieldResampler far_field_resampler(const BakeConfig& config, const ChunkSource& store) {
  struct State {
    BakeConfig config;
    const ChunkSource* store = nullptr;
    std::mutex mutex;
    std::optional<bool> whole;                     // trace the model itself (it fits one batch)
    std::int64_t cell = 0;                         // the cell `levels` was made for
    std::unique_ptr<LevelChunkSource> levels;
    std::unique_ptr<CubeSamplerFactory> factory;
    std::unique_ptr<CubeSampler> sampler;
  };
  auto state = std::make_shared<State>();
  state->config = config;
  state->store = &store;
  return [state](const CellRow& row, const Vec3d& eye, int face_size) {
    const std::lock_guard<std::mutex> lock(state->mutex);
    const BakeConfig& c = state->config;
    const std::size_t cap = std::size_t(c.embree_cache_mb) << 20;
    if (!state->whole) {
      std::uint64_t triangles = 0;
      for (const ChunkRef& r : state->store->query(state->store->model_bounds())) triangles += r.triangle_count;
      state->whole = triangles * kEstimatedBvhBytesPerTriangle <= cap / 2;
    }
    const bool new_cell = !*state->whole && (!state->levels || state->cell != row.id);
    if (new_cell) {
      state->sampler.reset();
      state->factory.reset();
      state->levels = std::make_unique<LevelChunkSource>(*state->store, row.bounds, 1.0, face_size);
      state->cell = row.id;
    }
    if (!state->sampler) {
      state->factory = std::make_unique<CubeSamplerFactory>(SampleBackend::embree, cap,
                                                            std::size_t(c.texture_cache_mb) << 20);
      state->sampler = state->factory->make();
      state->sampler->set_shading(cell_shading_lights(c));
    }
    SampleParams p = cell_sample_params(c);
    p.face_size = face_size;
    p.supersample = 1;
    const ChunkSource& traced = *state->whole ? *state->store : *state->levels;
    CubeSample cube = state->sampler->sample(eye, far_field_discard_box(row.bounds, row.cull_half_size, c), p, traced);
    state->sampler->end_work();
    return cube;
  };
}

}  // namespace

std::vector<MetaProblem> check_database_meta(const CellDb& db) {
  std::vector<MetaProblem> problems;
  std::optional<DescribedConfig> config;
  if (const auto text = db.meta("config")) {
    config = config_from_description(*text);
    for (const std::string& p : config->problems) problems.push_back({"config", p});
    if (config->problems.empty() && !config->config.regions.empty()) try {
        count_cells(config->config.regions, config->config.cell_size);
      } catch (const std::exception& e) {
        problems.push_back({"config", std::string("regions: ") + e.what()});
      }
  }
  if (const auto v = db.meta("cell_size")) try {
      const double size = parse_meta_double(db.path(), "cell_size", *v);
      if (!(size > 0)) throw std::runtime_error("'" + *v + "' is not a positive cell size");
      if (config && std::fabs(size - config->config.cell_size) > 5e-7 + 1e-6 * config->config.cell_size)
        throw std::runtime_error("'" + *v + "' is not the config's cells.size " +
                                 std::to_string(config->config.cell_size));
    } catch (const std::exception& e) {
      problems.push_back({"cell_size", e.what()});
    }
  if (const auto v = db.meta("up")) {
    if (*v != "z" && *v != "y")
      problems.push_back({"up", "'" + *v + "' is not z or y"});
    else if (config && *v != config->config.up)
      problems.push_back({"up", "'" + *v + "' is not the config's up=" + config->config.up});
  }
  if (const auto v = db.meta("store_hash"); v && !is_store_hash(*v))
    problems.push_back({"store_hash", "'" + *v + "' is not a content hash (a word of printable characters)"});
  for (const char* key : {"cells_total", "cells_selected"})
    if (const auto v = db.meta(key)) try {
        parse_meta_u64(db.path(), key, *v);
      } catch (const std::exception& e) {
        problems.push_back({key, e.what()});
      }
  return problems;
}

CellCheckSetup cell_check_setup(const CellDb& db, const std::filesystem::path& store_path) {
  CellCheckSetup setup;
  std::optional<BakeConfig> baked_with;
  if (const auto text = db.meta("config")) {
    DescribedConfig config = config_from_description(*text);
    if (config.problems.empty()) baked_with = config.config;
    if (config.problems.empty() && !config.config.regions.empty()) {
      const std::vector<Box3d> regions = config.config.regions;
      const double cell_size = config.config.cell_size;
      setup.context.place = [regions, cell_size](std::int64_t id) -> std::optional<CellPlace> {
        const std::optional<CellSpec> c = cell_of_id(regions, cell_size, id);
        if (!c) return std::nullopt;
        return CellPlace{c->region, c->gx, c->gy, c->gz, c->bounds};
      };
    }
  }
  const std::filesystem::path store =
      !store_path.empty() ? store_path : std::filesystem::path(db.meta("store").value_or(""));
  const auto baked_from = db.meta("store_hash");
  if (store.empty() || !baked_from) {
    setup.note = "no geometry store recorded: near lists and far geometry not compared with the store";
    return setup;
  }
  if (!std::filesystem::exists(store)) {
    setup.note = store.string() + " does not exist: near lists and far geometry not compared with the store";
    return setup;
  }
  try {
    auto opened = std::make_unique<GeometryStore>(store);
    if (opened->summary().content_hash != *baked_from) {
      setup.note = store.string() + " is not the store the cells were baked from (content hash " +
                   opened->summary().content_hash + ", not " + *baked_from +
                   "): near lists and far geometry not compared with it";
      return setup;
    }
    setup.store = std::move(opened);
    setup.context.store = setup.store.get();
    if (baked_with) setup.context.resample = far_field_resampler(*baked_with, *setup.store);
  } catch (const std::exception& e) {
    setup.note = std::string(e.what()) + ": near lists and far geometry not compared with the store";
  }
  return setup;
}

}  // namespace cellbake
