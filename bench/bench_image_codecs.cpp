// Colour codecs on real sampled cube faces: for each selected cell of a bake
// configuration, takes the cell-centre sample (as `cellbake bake` does with
// one sample), fills background texels as run_encode does, then encodes every
// face with each codec and quality and measures bytes, PSNR against the
// uncompressed face over covered pixels only (finite depth: the pixels the
// depth meshes texture), and single-thread encode / decode milliseconds.
//
//   bench_image_codecs configs/plant-demo.toml --store /tmp/h2/plant.store.db --cells 20-25
//   bench_image_codecs textured.toml --cells 1-4 --codecs jpeg:85,avif:50
//
// Not a Google Benchmark program: it needs a geometry store and reports
// error figures next to sizes and times.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/bench_program.h"
#include "bench/bench_sampled_faces.h"
#include "pipeline/bake_config.h"
#include "pipeline/cell_grid.h"
#include "stages/encode.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

struct Codec {
  std::string format;
  int quality = 0;
};

struct Args {
  std::string config, store, cells = "20-25";
  std::vector<Codec> codecs;
};

std::vector<Codec> default_codecs() {
  std::vector<Codec> c;
  for (int q : {50, 70, 85, 95}) c.push_back({"jpeg", q});
  for (int q : {50, 70, 85}) c.push_back({"webp", q});
  for (int q : {30, 45, 55, 65, 75}) c.push_back({"avif", q});
  for (int q : {50, 65, 75, 85}) c.push_back({"jxl", q});
  return c;
}

Args parse_args(int argc, char** argv) {
  Args a;
  std::vector<std::string> codecs;
  CLI::App app{"Colour codecs' bytes against PSNR on the covered pixels of baked faces", "bench_image_codecs"};
  app.add_option("config", a.config, "Bake configuration (TOML)")->required();
  app.add_option("--store", a.store, "Geometry store (default: the configuration's)");
  app.add_option("--cells", a.cells, "Cells to bake and measure")->capture_default_str();
  app.add_option("--codecs", codecs, "FORMAT:QUALITY,... (default: a sweep of jpeg, webp, avif, jxl)")->delimiter(',');
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::exit(app.exit(e));
  }
  for (const std::string& item : codecs) {
    const std::size_t colon = item.find(':');
    if (colon == std::string::npos) throw std::invalid_argument("codec '" + item + "' is not FORMAT:QUALITY");
    a.codecs.push_back({item.substr(0, colon), std::stoi(item.substr(colon + 1))});
  }
  if (a.codecs.empty()) a.codecs = default_codecs();
  return a;
}

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

struct Point {
  double bytes = 0, sq_error = 0, samples = 0, encode_ms = 0, decode_ms = 0, worst_face_psnr = 1e9;
};

int run(int argc, char** argv) {
  const Args args = parse_args(argc, argv);
  if (!std::getenv("LP_NUM_THREADS")) setenv("LP_NUM_THREADS", "1", 1);
  BakeConfig config = load_bake_config(args.config);
  if (!args.store.empty()) config.store = args.store;
  const std::vector<SampledFace> faces =
      sample_centre_faces(config, select_cells(enumerate_cells(config.regions, config.cell_size), args.cells));
  const int n = config.face_size;
  std::size_t covered = 0;
  for (const SampledFace& f : faces) covered += f.covered_count;
  std::printf("%zu faces of %d^2, %.1f %% of their pixels covered\n", faces.size(), n,
              100.0 * double(covered) / (double(faces.size()) * n * n));
  std::printf("%-10s %8s %10s %12s %14s %10s %10s\n", "codec", "quality", "KB/face", "PSNR dB", "worst face dB",
              "enc ms", "dec ms");
  for (const Codec& codec : args.codecs) {
    Point p;
    for (const SampledFace& f : faces) {
      auto t0 = Clock::now();
      const std::vector<std::uint8_t> bytes = encode_image(f.color, n, n, {codec.format, codec.quality});
      p.encode_ms += ms_since(t0);
      t0 = Clock::now();
      const DecodedImage img = decode_image(bytes);
      p.decode_ms += ms_since(t0);
      const double se = covered_sq_error(f, img.pixels);
      p.bytes += double(bytes.size());
      p.sq_error += se;
      p.samples += 3.0 * double(f.covered_count);
      p.worst_face_psnr = std::min(p.worst_face_psnr, psnr(se, 3.0 * double(f.covered_count)));
    }
    const double k = double(faces.size());
    std::printf("%-10s %8d %10.1f %12.2f %14.2f %10.2f %10.2f\n", codec.format.c_str(), codec.quality,
                p.bytes / k / 1024, psnr(p.sq_error, p.samples), p.worst_face_psnr, p.encode_ms / k, p.decode_ms / k);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace
}  // namespace cellbake

int main(int argc, char** argv) {
  return cellbake::run_bench_program("bench_image_codecs", cellbake::run, argc, argv);
}
