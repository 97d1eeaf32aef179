#include "pipeline/ingest.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <limits>
#include <map>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "pipeline/input_error.h"
#include "pipeline/readers/model_reader.h"
#include "pipeline/readers/contained_paths.h"
#include "pipeline/texture_import.h"
#include "stages/chunking.h"
#include "stages/hashing.h"
#include "storage/geometry_store.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Holds triangles in memory up to a byte budget, then continues in a
// temporary file that is mapped back for random access: small and medium
// models never touch the disk, huge ones keep memory bounded.
class TriangleSpill {
 public:
  TriangleSpill(const std::filesystem::path& file, std::size_t memory_budget_bytes)
      : path_(file), memory_limit_(std::max<std::size_t>(1, memory_budget_bytes / sizeof(Triangle))) {}
  ~TriangleSpill() {
    if (out_) std::fclose(out_);
    if (map_) munmap(map_, map_bytes_);
    if (spilled_) {
      std::error_code ec;
      std::filesystem::remove(path_, ec);
    }
  }
  void add(const Triangle& t) {
    ++count_;
    if (!spilled_) {
      memory_.push_back(t);  // a deque: no reallocation copies, no 2x peak
      if (memory_.size() > memory_limit_) flush_to_file();
      return;
    }
    buffer_.push_back(t);
    if (buffer_.size() == kFileBuffer) flush_to_file();
  }
  std::uint64_t count() const { return count_; }
  bool spilled() const { return spilled_; }
  // Finishes adding; triangles are then readable by index.
  void finish() {
    if (!spilled_) return;
    flush_to_file();
    if (std::fclose(out_) != 0) throw std::runtime_error(path_.string() + ": cannot write spill file");
    out_ = nullptr;
    int fd = ::open(path_.c_str(), O_RDONLY);
    if (fd < 0) throw std::runtime_error(path_.string() + ": cannot reopen spill file");
    map_bytes_ = count_ * sizeof(Triangle);
    map_ = mmap(nullptr, map_bytes_, PROT_READ, MAP_SHARED, fd, 0);
    ::close(fd);
    if (map_ == MAP_FAILED) {
      map_ = nullptr;
      throw std::runtime_error(path_.string() + ": cannot map spill file");
    }
  }
  const Triangle& operator[](std::size_t i) const {
    return spilled_ ? static_cast<const Triangle*>(map_)[i] : memory_[i];
  }

 private:
  static constexpr std::size_t kFileBuffer = 1 << 14;
  void flush_to_file() {
    if (!spilled_) {
      out_ = std::fopen(path_.c_str(), "wb");
      if (!out_) throw std::runtime_error(path_.string() + ": cannot create spill file");
      spilled_ = true;
      for (const Triangle& t : memory_) write(&t, 1);
      std::deque<Triangle>().swap(memory_);
    }
    write(buffer_.data(), buffer_.size());
    buffer_.clear();
  }
  void write(const Triangle* t, std::size_t n) {
    if (n && std::fwrite(t, sizeof(Triangle), n, out_) != n)
      throw std::runtime_error(path_.string() + ": cannot write spill file (disk full?)");
  }
  std::filesystem::path path_;
  std::size_t memory_limit_;
  std::FILE* out_ = nullptr;
  bool spilled_ = false;
  std::deque<Triangle> memory_;
  std::vector<Triangle> buffer_;
  std::uint64_t count_ = 0;
  void* map_ = nullptr;
  std::size_t map_bytes_ = 0;
};

std::string hash_file(const std::filesystem::path& file, std::uint64_t& bytes) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), "", "cannot open file");
  Hasher h;
  std::vector<char> buf(1 << 20);
  bytes = 0;
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    h.bytes(buf.data(), n);
    bytes += n;
  }
  return h.hex();
}

struct StoredTexture {
  std::int64_t id = 0;
  bool has_alpha = false;
};

// Imports the texture `material` (index `index` of `info`, read from `model`)
// names, once per distinct image, and sets its texture_id and alpha_test; an
// image that cannot be read becomes a warning and the material stays untextured.
// Adds `warning` to the report's texture warnings unless it is there already
// (materials of the same name and texture, e.g. assimp's "DefaultMaterial").
void warn_texture(IngestReport& report, std::string warning) {
  if (std::find(report.texture_warnings.begin(), report.texture_warnings.end(), warning) ==
      report.texture_warnings.end())
    report.texture_warnings.push_back(std::move(warning));
}

void attach_texture(Material& material, std::uint32_t index, const ModelInfo& info,
                    const std::filesystem::path& model, const IngestParams& params, GeometryStoreWriter& writer,
                    std::map<std::string, StoredTexture>& texture_ids, IngestReport& report) {
  TextureInput input;
  if (const auto found = info.textures.find(index); found != info.textures.end()) {
    input = found->second;
  } else {
    const std::filesystem::path path(material.texture);
    input.file = path.is_absolute() ? path : locate_referenced_file(model.parent_path(), material.texture);
  }
  const bool embedded = input.file.empty();
  if (!embedded && !params.allow_outside_paths && !path_inside_folder(model.parent_path(), input.file)) {
    warn_texture(report, model.filename().string() + ": material '" + material.name + "': texture '" +
                             input.file.string() + "': " + kOutsideFolder + ": material colour used");
    material.texture_id = 0;
    return;
  }
  const std::string key = embedded ? model.string() + "#" + material.texture : input.file.string();
  const std::string shown = embedded ? material.texture + " (embedded)" : input.file.string();
  bool has_alpha = false;
  if (const auto known = texture_ids.find(key); known != texture_ids.end()) {
    material.texture_id = known->second.id;
    has_alpha = known->second.has_alpha;
  } else {
    try {
      const TextureImage image = import_texture(input, "'" + shown + "'", {params.max_texture_size});
      material.texture_id = writer.add_texture(image, shown);
      ++report.textures;
      report.texture_bytes += image.bytes();
      // Known only after a successful import; failures are retried (and warned) per material.
      texture_ids[key] = {material.texture_id, image.has_alpha};
      has_alpha = image.has_alpha;
    } catch (const std::exception& e) {
      warn_texture(report, model.filename().string() + ": material '" + material.name + "': " + e.what() +
                               ": material colour used");
      material.texture_id = 0;
      return;
    }
  }
  material.alpha_test = has_alpha && input.alpha_allowed;
}

// Sets report.up, up_source, up_from_geometry and up_warning: --up first,
// then the files' convention, then a sure answer from the geometry; a given or
// conventional axis the geometry contradicts is kept, with a warning.
void choose_up_axis(const std::string& given, const std::string& from_files, bool files_disagree,
                    const std::vector<std::string>& claims, const UpAxisGuess& geometry, IngestReport& report) {
  report.up_from_geometry = geometry;
  std::string disagreement;
  if (files_disagree) {
    disagreement = "the files disagree (";
    for (std::size_t i = 0; i < claims.size(); ++i) disagreement += (i ? "; " : "") + claims[i];
    disagreement += ")";
  }
  if (!given.empty()) {
    report.up = given, report.up_source = "--up";
  } else if (!from_files.empty() && !files_disagree) {
    report.up = from_files;  // up_source: the file's reason, set while reading
  } else if (!geometry.axis.empty()) {
    report.up = geometry.axis;
    report.up_source = (files_disagree ? disagreement + "; " : "") + "detected from the geometry: " + geometry.evidence;
    return;
  } else {
    report.up_source = (files_disagree ? disagreement : "the file format does not record one") +
                       " and the geometry is not conclusive: " + geometry.evidence;
    return;
  }
  // Only flat planes contradict a given or conventional axis: most area facing
  // an axis (terrain's evidence) is also what a standing sign or facade shows.
  if (geometry.axis.empty() || geometry.from_facing) return;
  if (geometry.axis == report.up) {
    report.up_source += "; the geometry agrees";
    return;
  }
  report.up_warning = "warning: the up axis recorded is " + report.up + " (" + report.up_source +
                      ") but the geometry looks " + geometry.axis + "-up: " + geometry.evidence +
                      (given.empty() ? "; `ingest --up " + geometry.axis + "` records " + geometry.axis
                                     : "");
}

// What the readers get from ingest's parameters.
ReadOptions read_options(const IngestParams& params) {
  ReadOptions options;
  options.allow_outside_paths = params.allow_outside_paths;
  options.import_in_child_process = params.import_in_child_process;
  options.import_memory_bytes = params.import_memory_bytes;
  options.import_seconds = params.import_seconds;
  return options;
}

// What reading the model files gathers for the store, beside the triangles
// themselves (in the spill): materials (each file's after the previous ones'),
// the files' provenance, a sort key per kept triangle, the files' claims about
// the up axis, the kept triangles' bounds, and the textures imported so far.
struct ReadModels {
  std::map<std::string, StoredTexture> texture_ids;  // by resolved file path or embedded-image key
  std::vector<Material> materials;
  std::vector<SourceFileRecord> sources;
  std::vector<TriangleKey> keys;
  // The store's content hash is the writer's, over what it stores (chunks,
  // materials, textures): whatever reaches the store through any file a model
  // names (.mtl colours, textures, glTF buffers) or any parameter changes it.
  // The up axis is metadata, not content: a store's hash (and so every bake
  // hash) does not change when only the recorded axis does.
  std::vector<std::string> up_claims;  // "FILE: y (reason)" for files that say
  std::string up_from_files;
  bool up_disagree = false;
  Box3d read_bounds;  // of the kept triangles: fixes the bins of the up-axis evidence
};

// What a model file says beside its triangles: its materials (textures
// imported), its up axis claim, triangulated polygons, warnings and vertex
// colour notes.
void record_model_info(const ModelInfo& info, const std::filesystem::path& model, const IngestParams& params,
                       GeometryStoreWriter& writer, ReadModels& read, IngestReport& report) {
  for (std::uint32_t m = 0; m < info.materials.size(); ++m) {
    Material material = info.materials[m];
    if (!material.texture.empty())
      attach_texture(material, m, info, model, params, writer, read.texture_ids, report);
    read.materials.push_back(material);
  }
  if (!info.up.empty()) {
    read.up_claims.push_back(model.filename().string() + ": " + info.up + " (" + info.up_source + ")");
    if (read.up_from_files.empty()) {
      read.up_from_files = info.up;
      report.up_source = model.filename().string() + ": " + info.up_source;
    }
    read.up_disagree |= info.up != read.up_from_files;
  }
  report.polygons_triangulated += info.polygons_triangulated;
  for (const std::string& w : info.warnings) report.input_warnings.push_back(model.filename().string() + ":" + w);
  if (const std::string note = describe_vertex_colours(info); !note.empty())
    report.vertex_colour_notes.push_back(model.filename().string() + ": " + note);
}

// Reads one model file: its triangles translated, checked, the degenerate ones
// skipped and the rest kept in the spill with their keys; then its materials
// and the rest of what it says; its provenance record added.
void read_one_model(const std::filesystem::path& model, const IngestParams& params, TriangleSpill& spill,
                    GeometryStoreWriter& writer, ReadModels& read, IngestReport& report,
                    const ProgressCallback& progress) {
  SourceFileRecord src;
  src.path = model.string();
  require_regular_file(model);
  src.hash = hash_file(model, src.bytes);  // provenance (the sources table), not the content hash
  const auto material_offset = static_cast<std::uint32_t>(read.materials.size());
  std::uint64_t file_triangles = 0;
  const bool translate = params.translate != Vec3d{0, 0, 0};
  ModelInfo info = read_model(model, [&](const Triangle& in) {
    Triangle t = in;
    ++report.triangles_read;
    if (translate)
      for (auto& p : t.p) p = p + params.translate;
    for (const auto& p : t.p)
      if (!is_finite(p)) throw InputError(model.string(), "", "non-finite coordinate after translation");
    if (is_degenerate(t)) {
      ++report.skipped_degenerate;
      return;
    }
    if (spill.count() >= std::numeric_limits<std::uint32_t>::max())
      throw InputError(model.string(), "", "more than 4294967295 triangles are not supported");
    t.material += material_offset;
    for (const auto& p : t.p) read.read_bounds.expand(p);
    read.keys.push_back(make_triangle_key(t, static_cast<std::uint32_t>(spill.count())));
    spill.add(t);
    ++file_triangles;
    if (progress && (report.triangles_read & 0xFFFF) == 0)
      progress("read " + model.filename().string(), report.triangles_read, 0);
  }, read_options(params));
  if (progress) progress("read " + model.filename().string(), report.triangles_read, 0);  // the file's last count
  record_model_info(info, model, params, writer, read, report);
  src.triangles = file_triangles;
  read.sources.push_back(src);
}

// The chunk of the triangles in `r` (indices into `keys`). Exact duplicates
// share shape hash and centroid; the first copy (lowest index) is kept.
Chunk build_chunk_without_duplicates(const ChunkRange& r, const std::vector<TriangleKey>& keys,
                                     const TriangleSpill& spill) {
  std::vector<std::size_t> order;
  order.reserve(r.end - r.begin);
  for (std::size_t k = r.begin; k < r.end; ++k) order.push_back(k);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if (keys[a].shape_hash != keys[b].shape_hash) return keys[a].shape_hash < keys[b].shape_hash;
    return keys[a].index < keys[b].index;
  });
  std::vector<char> drop(r.end - r.begin, 0);
  for (std::size_t i = 0; i < order.size(); ++i) {
    if (drop[order[i] - r.begin]) continue;
    for (std::size_t j2 = i + 1; j2 < order.size() && keys[order[j2]].shape_hash == keys[order[i]].shape_hash; ++j2)
      if (keys[order[j2]].centroid == keys[order[i]].centroid &&
          same_corners(spill[keys[order[i]].index], spill[keys[order[j2]].index]))
        drop[order[j2] - r.begin] = 1;
  }
  std::vector<const Triangle*> tris;
  tris.reserve(r.end - r.begin);
  for (std::size_t k = r.begin; k < r.end; ++k)
    if (!drop[k - r.begin]) tris.push_back(&spill[keys[k].index]);
  return build_chunk(tris);
}

// Builds the chunks in parallel batches and writes them in order
// (deterministic ids), each with its simplified levels, counted in the report
// and fed to the up-axis evidence; empty chunks are not written.
void write_chunks(const std::vector<ChunkRange>& ranges, const std::vector<TriangleKey>& keys,
                  const TriangleSpill& spill, const IngestParams& params, const ParallelFor& parallel_for,
                  GeometryStoreWriter& writer, UpAxisEvidence& up_evidence, IngestReport& report,
                  const ProgressCallback& progress) {
  constexpr std::size_t kBatch = 256;
  std::vector<Chunk> batch;
  std::vector<std::vector<ChunkLod>> batch_lods;
  for (std::size_t first = 0; first < ranges.size(); first += kBatch) {
    const std::size_t n = std::min(kBatch, ranges.size() - first);
    batch.assign(n, Chunk{});
    batch_lods.assign(n, {});
    parallel_for(n, [&](std::size_t j) {
      batch[j] = build_chunk_without_duplicates(ranges[first + j], keys, spill);
      // The far field's simplified levels (stages/chunk_lod.h).
      if (params.chunk_lods) batch_lods[j] = build_chunk_lods(batch[j], params.lod);
    });
    for (std::size_t j = 0; j < n; ++j) {
      const Chunk& c = batch[j];
      if (c.indices.empty()) continue;
      report.triangles_stored += c.triangle_count();
      report.vertices += c.positions.size();
      report.bounds.expand(c.bounds);
      const std::int64_t id = writer.add_chunk(c);
      writer.add_chunk_lods(id, batch_lods[j]);
      for (const ChunkLod& l : batch_lods[j]) ++report.chunk_lods, report.lod_triangles += l.ref.triangle_count;
      up_evidence.add_chunk(c);
      ++report.chunks;
    }
    if (progress) progress("write", first + n, ranges.size());
  }
}

// The store's summary row, from the report, and the store finished.
void finish_store(GeometryStoreWriter& writer, const IngestReport& report, const IngestParams& params) {
  StoreSummary summary;
  summary.bounds = report.bounds;
  summary.triangles = report.triangles_stored;
  summary.vertices = report.vertices;
  summary.chunks = report.chunks;
  summary.skipped_degenerate = report.skipped_degenerate;
  summary.skipped_duplicate = report.skipped_duplicate;
  summary.units = params.units;
  summary.content_hash = report.content_hash;
  summary.up = report.up;
  summary.up_source = report.up.empty() ? "" : report.up_source;
  writer.finish(summary);
}

}  // namespace

IngestReport ingest_models(const std::vector<std::filesystem::path>& models, const std::filesystem::path& store,
                           const IngestParams& params, const ParallelFor& parallel_for,
                           const ProgressCallback& progress) {
  if (models.empty()) throw std::invalid_argument("ingest: no model files given");
  if (params.max_chunk_triangles < 1) throw std::invalid_argument("ingest: max_chunk_triangles must be >= 1");
  IngestReport report;
  const auto t_read = Clock::now();
  const std::filesystem::path temp_dir =
      params.temp_dir.empty() ? std::filesystem::absolute(store).parent_path() : params.temp_dir;
  std::filesystem::create_directories(temp_dir);
  TriangleSpill spill(temp_dir / (store.filename().string() + ".spill-" + std::to_string(::getpid())),
                      params.memory_budget_bytes);

  if (params.max_texture_size < 1) throw std::invalid_argument("ingest: max_texture_size must be >= 1");
  GeometryStoreWriter writer(store);
  ReadModels read;
  if (!params.up.empty() && params.up != "z" && params.up != "y")
    throw std::invalid_argument("ingest: up must be \"z\" or \"y\"");
  for (const auto& model : models) read_one_model(model, params, spill, writer, read, report, progress);
  spill.finish();
  if (spill.count() == 0)
    throw InputError(models.front().string(), "",
                     report.triangles_read ? "model has only degenerate triangles" : "model contains no triangles");
  report.read_seconds = seconds_since(t_read);

  const auto t_chunk = Clock::now();
  if (progress) progress("chunk", 0, 0);
  const std::vector<ChunkRange> ranges = split_into_chunks(read.keys, params.max_chunk_triangles);
  if (progress) progress("chunk", read.keys.size(), read.keys.size());
  report.chunk_seconds = seconds_since(t_chunk);

  const auto t_write = Clock::now();
  UpAxisEvidence up_evidence(read.read_bounds);  // fed the chunks as they are written, in order
  for (std::size_t i = 0; i < read.materials.size(); ++i)
    writer.add_material(static_cast<std::uint32_t>(i), read.materials[i]);
  for (const auto& s : read.sources) writer.add_source(s);
  write_chunks(ranges, read.keys, spill, params, parallel_for, writer, up_evidence, report, progress);
  report.skipped_duplicate = spill.count() - report.triangles_stored;
  report.content_hash = writer.content_hash();

  choose_up_axis(params.up, read.up_from_files, read.up_disagree, read.up_claims, up_evidence.guess(), report);
  finish_store(writer, report, params);
  report.write_seconds = seconds_since(t_write);
  if (progress) progress("done", 0, 0);
  return report;
}

}  // namespace cellbake
