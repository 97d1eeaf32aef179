// Colour codecs on real sampled cube faces: for each selected cell of a bake
// configuration, takes the cell-centre sample (as `cellbake bake` does with
// one sample), fills background texels as run_encode does, then encodes every
// face with each codec and quality and measures bytes, PSNR and SSIM against
// the uncompressed face over covered pixels only (finite depth: the pixels the
// depth meshes texture), and single-thread encode / decode milliseconds.
// PSNR: over all covered pixels of all faces, and the median and worst face.
// SSIM (viewer/image_metrics masked_ssim: 8x8 windows wholly on covered
// pixels): median and worst face, over the faces with such a window.
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
#include "stages/encode/encode.h"
#include "viewer/image_metrics.h"

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
  CLI::App app{"Colour codecs' bytes against PSNR and SSIM on the covered pixels of baked faces", "bench_image_codecs"};
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
  double bytes = 0, sq_error = 0, samples = 0, encode_ms = 0, decode_ms = 0;
  std::vector<double> face_psnr, face_ssim;
};

// Median (mean of the middle two for an even count); NaN when empty.
double median_of(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

double min_of(const std::vector<double>& v) {
  return v.empty() ? std::nan("") : *std::min_element(v.begin(), v.end());
}

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
  std::printf("%-6s %7s %8s %8s %11s %10s %11s %10s %8s %8s\n", "codec", "quality", "KB/face", "PSNR dB",
              "median face", "worst face", "SSIM median", "SSIM worst", "enc ms", "dec ms");
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
      p.face_psnr.push_back(psnr(se, 3.0 * double(f.covered_count)));
      const double ssim = masked_ssim(img.pixels, f.color, n, n, f.covered);
      if (!std::isnan(ssim)) p.face_ssim.push_back(ssim);
    }
    const double k = double(faces.size());
    std::printf("%-6s %7d %8.1f %8.2f %11.2f %10.2f %11.4f %10.4f %8.2f %8.2f\n", codec.format.c_str(), codec.quality,
                p.bytes / k / 1024, psnr(p.sq_error, p.samples), median_of(p.face_psnr), min_of(p.face_psnr),
                median_of(p.face_ssim), min_of(p.face_ssim), p.encode_ms / k, p.decode_ms / k);
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace
}  // namespace cellbake

int main(int argc, char** argv) {
  return cellbake::run_bench_program("bench_image_codecs", cellbake::run, argc, argv);
}
