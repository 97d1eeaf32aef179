// Imports in a child process (issue #37, pipeline/readers/isolated_read.h):
// a model reads the same isolated as in process; a crash, a runaway
// allocation or an endless import in the child is an InputError naming the
// file, and the calling process lives on.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "pipeline/input_error.h"
#include "pipeline/readers/isolated_read.h"
#include "pipeline/readers/model_reader.h"
#include "tests/fixture_hostile_models.h"
#include "tests/fixture_textured.h"
#include "tests/test_support.h"

#if defined(__SANITIZE_ADDRESS__)
#define CELLBAKE_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define CELLBAKE_TEST_ASAN 1
#endif
#endif

namespace cellbake {
namespace {

using test::TempDir;
using test::write_text;

struct Read {
  ModelInfo info;
  std::vector<Triangle> triangles;
  std::string error;  // the InputError's message, or ""
};

Read read_with(const std::filesystem::path& file, bool isolated) {
  Read r;
  ReadOptions options;
  options.import_in_child_process = isolated;
  options.import_memory_bytes = std::uint64_t{4} << 30;
  options.import_seconds = 60;
  try {
    r.info = read_model(file, [&](const Triangle& t) { r.triangles.push_back(t); }, options);
  } catch (const InputError& e) {
    r.error = e.what();
  }
  return r;
}

void expect_same_triangles(const std::vector<Triangle>& a, const std::vector<Triangle>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(a[i].p[k].x, b[i].p[k].x);
      EXPECT_EQ(a[i].p[k].y, b[i].p[k].y);
      EXPECT_EQ(a[i].p[k].z, b[i].p[k].z);
      EXPECT_EQ(a[i].color[k], b[i].color[k]);
      EXPECT_EQ(a[i].uv[k], b[i].uv[k]);
      EXPECT_EQ(a[i].normal[k], b[i].normal[k]);
    }
    EXPECT_EQ(a[i].has_normals, b[i].has_normals);
    EXPECT_EQ(a[i].material, b[i].material);
  }
}

void expect_same_info(const ModelInfo& a, const ModelInfo& b) {
  EXPECT_EQ(a.materials, b.materials);
  ASSERT_EQ(a.textures.size(), b.textures.size());
  for (const auto& [m, t] : a.textures) {
    ASSERT_TRUE(b.textures.count(m)) << m;
    const TextureInput& u = b.textures.at(m);
    EXPECT_EQ(t.file, u.file);
    EXPECT_EQ(t.encoded, u.encoded);
    EXPECT_EQ(t.format_hint, u.format_hint);
    EXPECT_EQ(t.texels, u.texels);
    EXPECT_EQ(t.width, u.width);
    EXPECT_EQ(t.height, u.height);
    EXPECT_EQ(t.wrap_u, u.wrap_u);
    EXPECT_EQ(t.wrap_v, u.wrap_v);
    EXPECT_EQ(t.alpha_allowed, u.alpha_allowed);
  }
  EXPECT_EQ(a.vertex_colours, b.vertex_colours);
  EXPECT_EQ(a.uniform_vertex_colour, b.uniform_vertex_colour);
  EXPECT_EQ(a.triangles_emitted, b.triangles_emitted);
  EXPECT_EQ(a.polygons_triangulated, b.polygons_triangulated);
  EXPECT_EQ(a.format, b.format);
  EXPECT_EQ(a.up, b.up);
  EXPECT_EQ(a.up_source, b.up_source);
  EXPECT_EQ(a.warnings, b.warnings);
}

// No child of this process is left unreaped.
void expect_no_children_left() {
  int status = 0;
  EXPECT_EQ(::waitpid(-1, &status, WNOHANG), -1);
  EXPECT_EQ(errno, ECHILD);
}

TEST(IsolatedRead, ModelsReadTheSameInAChildProcessAsInProcess) {
  TempDir dir;
  // An embedded PNG texture with clamped wrap modes, a material, texcoords.
  test::write_bytes(dir / "quad.glb",
                    test::textured_quad_glb(test::checker_wall(), test::png_of_bottom_up(test::checker_texels(), 64, 64)));
  // Shared children (8 placements of one mesh), COLLADA and X3D nestings.
  write_text(dir / "shared.gltf", test::gltf_node_chain(3, 2));
  write_text(dir / "nested.dae", test::collada_nested_nodes(50));
  write_text(dir / "nested.x3d", test::x3d_nested_transforms(50));
  // An OBJ (our own reader: never isolated) and a glTF with a dropped-face warning.
  write_text(dir / "t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  for (const char* name : {"quad.glb", "shared.gltf", "nested.dae", "nested.x3d", "t.obj"}) {
    SCOPED_TRACE(name);
    const Read in = read_with(dir / name, false), isolated = read_with(dir / name, true);
    EXPECT_EQ(in.error, "");
    EXPECT_EQ(isolated.error, "");
    EXPECT_GT(in.triangles.size(), 0u);
    expect_same_triangles(in.triangles, isolated.triangles);
    expect_same_info(in.info, isolated.info);
  }
  EXPECT_EQ(read_with(dir / "quad.glb", true).info.textures.size(), 1u);
  EXPECT_EQ(read_with(dir / "shared.gltf", true).triangles.size(), 8u);
  expect_no_children_left();
}

TEST(IsolatedRead, ReadErrorsInTheChildKeepTheirMessages) {
  TempDir dir;
  write_text(dir / "chain.gltf", test::gltf_node_chain(100000));
  write_text(dir / "deep.dae", test::collada_nested_nodes(10000));
  write_text(dir / "broken.gltf", R"({"asset":{"version":"2.0"},"nodes":[)");
  for (const char* name : {"chain.gltf", "deep.dae", "broken.gltf"}) {
    SCOPED_TRACE(name);
    const Read in = read_with(dir / name, false), isolated = read_with(dir / name, true);
    EXPECT_NE(in.error.find(name), std::string::npos) << in.error;
    EXPECT_EQ(in.error, isolated.error);
  }
  expect_no_children_left();
}

// The mechanism with read functions that misbehave as an importer might.
// Emits `count` triangles, then calls `then`.
ModelInfo emit_then(const TriangleCallback& emit, const std::function<void()>& then, int count = 1) {
  Triangle t;
  t.p = {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0, 1, 0}};
  for (int i = 0; i < count; ++i) emit(t);
  then();
  return ModelInfo{};
}

std::string isolated_error(const std::function<void()>& misbehave, const IsolationLimits& limits) {
  try {
    read_in_child_process(
        "hostile.dae", "assimp", [&](const TriangleCallback& emit) { return emit_then(emit, misbehave); },
        [&](const Triangle&) {}, limits);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(IsolatedRead, ACrashInTheImporterIsAnErrorNamingTheFileAndSignal) {
  EXPECT_EQ(isolated_error([] { ::raise(SIGSEGV); }, {}),
            "hostile.dae: assimp crashed while reading it (signal 11, Segmentation fault)");
  EXPECT_EQ(isolated_error([] { std::abort(); }, {}),
            "hostile.dae: assimp crashed while reading it (signal 6, Aborted)");
  expect_no_children_left();
}

TEST(IsolatedRead, AssimpCrashingOnAFileIsAnIngestErrorNamingTheFile) {
  TempDir dir;
  // Frames nested 100,000 deep in the binary .x format: assimp's .x parser
  // overflows its stack (the check before import scans only text .x files);
  // in the child that is an error, not cellbake's death.
  write_text(dir / "deep.x", test::directx_binary_nested_frames(100000));
  const test::CommandResult r =
      test::run_cellbake("ingest " + (dir / "deep.x").string() + " --store " + (dir / "s.db").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("deep.x: assimp crashed while reading it (signal 11, Segmentation fault)"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "s.db"));
  // The same format nested 10 deep reads.
  write_text(dir / "frames.x", test::directx_nested_frames(10));
  const test::CommandResult ok =
      test::run_cellbake("ingest " + (dir / "frames.x").string() + " --store " + (dir / "t.db").string());
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
}

TEST(IsolatedRead, AnImportOverTheMemoryLimitIsStopped) {
#ifdef CELLBAKE_TEST_ASAN
  GTEST_SKIP() << "AddressSanitizer's allocator reports the limit as its own error";
#endif
  IsolationLimits limits;
  limits.memory_bytes = std::uint64_t{256} << 20;
  std::vector<std::vector<char>> held;
  EXPECT_EQ(isolated_error(
                [&] {
                  for (int i = 0; i < 64; ++i) held.emplace_back(std::size_t{64} << 20);  // 4 GiB at most
                },
                limits),
            "hostile.dae: assimp needed more than 0.25 GB of memory to read it and was stopped (the import "
            "memory limit)");
  EXPECT_TRUE(held.empty());  // that happened in the child
  expect_no_children_left();
}

TEST(IsolatedRead, AnImportOverTheTimeLimitIsStopped) {
  IsolationLimits limits;
  limits.seconds = 0.5;
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(isolated_error([] { std::this_thread::sleep_for(std::chrono::seconds(60)); }, limits),
            "hostile.dae: assimp took more than 0.5 s to read it and was stopped (the import time limit)");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 30.0);
  expect_no_children_left();
}

TEST(IsolatedRead, AnErrorInTheCallersEmitStopsTheChild) {
  const auto start = std::chrono::steady_clock::now();
  try {
    read_in_child_process(
        "hostile.dae", "assimp",
        [&](const TriangleCallback& emit) {  // more than one batch, then a long wait
          return emit_then(emit, [] { std::this_thread::sleep_for(std::chrono::seconds(60)); }, 10000);
        },
        [](const Triangle&) { throw InputError("hostile.dae", "", "refused by the caller"); }, {});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "hostile.dae: refused by the caller");
  }
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 30.0);  // not waited for
  expect_no_children_left();
}

// COLLADA whose triangles claim a count of 25 million, padded with a
// comment to 25 MB so the count is one the file could hold (collada_node_graph.h):
// assimp reserves 3 size_t indices per triangle (600 MB) before it reads the 3 the file has.
std::string collada_claiming_25_million_triangles() {
  std::string s = test::collada_nested_nodes(1);
  const std::string count = R"(<triangles count="1">)";
  s.replace(s.find(count), count.size(), R"(<triangles count="25000000">)");
  return s + "<!--" + std::string(25'000'000, ' ') + "-->";
}

TEST(IsolatedRead, IngestRefusesAnImportOverItsMemoryLimitNamingTheFile) {
#ifdef CELLBAKE_TEST_ASAN
  GTEST_SKIP() << "AddressSanitizer's allocator reports the limit as its own error";
#endif
  TempDir dir;
  write_text(dir / "claims.dae", collada_claiming_25_million_triangles());
  const test::CommandResult r = test::run_cellbake("ingest " + (dir / "claims.dae").string() + " --store " +
                                                   (dir / "s.db").string() + " --import-memory-gb 0.5");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("claims.dae: assimp needed more than 0.5 GB of memory to read it"), std::string::npos)
      << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "s.db"));
}

}  // namespace
}  // namespace cellbake
