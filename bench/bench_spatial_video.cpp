// Spatial video (issue #16 item 3): do neighbouring cells' cube faces, coded
// as a video sequence, cost fewer bytes than the bake's per-face AVIF at equal
// error, and can one cell still be decoded alone within the viewer's budget?
// The thesis' "spatial MPEG" (MPEGWALK; Wilson, UNC 2002, ch. 4)
// codes the faces of cells along a space-filling curve as a video.
//
// For the selected cells (one centre sample each, as bench_image_codecs:
// bench_sampled_faces.h), in serpentine order over the grid (rows along x,
// every other row reversed: consecutive cells are neighbours), each face
// direction is its own sequence (faces without covered pixels left out). Each
// sequence is cut into groups of GOP consecutive faces, each group coded as
// one closed stream (keyframe, then P/B frames) so any cell decodes alone
// from its group's keyframe. Compared side by side, several quality points
// each: (a) the bake's per-face AVIF (encode_image, 4:4:4 speed 8), (b) AV1
// via libavcodec (libaom-av1, yuv444p, decoded by libdav1d), (c) HEVC
// (libx265, yuv444p, decoded by libavcodec's hevc). Reported per point: bytes
// per face and per cell (a group's bytes shared by its faces), PSNR over
// covered pixels against the uncompressed face (pooled, median face, worst
// face), mean SSIM of covered 8x8 windows, encode ms per face, and the
// random-access decode cost on one thread: ms until a face is ready when its
// group is decoded from the keyframe (mean, worst face; per cell: the sum of
// its faces). Last, every curve's bytes at the PSNR of AVIF at the bake's
// quality (log-bytes interpolated), against AVIF's.
//
//   bench_spatial_video configs/plant-demo.toml --store /tmp/demo4/plant.store.db --cells 18-44
//   bench_spatial_video cfg.toml --cells 0-17 --gops 1,8 --av1-crf 30 --x265-crf 26 --avif 55
//
// Not a Google Benchmark program: it needs a geometry store and reports error
// figures next to sizes and times. Built only where pkg-config finds
// libavcodec, libavutil and libswscale (scripts/install-deps.sh bench).
#include <CLI/CLI.hpp>

extern "C" {
#include <libavutil/log.h>
}

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "bench/bench_program.h"
#include "bench/bench_sampled_faces.h"
#include "bench/bench_video_group.h"
#include "pipeline/bake_config.h"
#include "pipeline/cell_grid.h"
#include "stages/encode/encode.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

struct Args {
  std::string config, store, cells = "18-44";
  std::vector<int> gops = {1, 4, 8, 16};
  std::vector<int> avif = {45, 55, 65};
  std::vector<double> av1_crf = {22, 29, 36, 43};
  std::vector<double> x265_crf = {18, 24, 30, 36};
  int baseline_quality = 55;
  int aom_cpu_used = 6;
  std::string aom_usage = "good", x265_preset = "medium";
};

Args parse_args(int argc, char** argv) {
  Args a;
  CLI::App app{"Neighbouring cells' faces as video (AV1, HEVC) against per-face AVIF: bytes, covered-pixel PSNR, "
               "random-access decode",
               "bench_spatial_video"};
  app.add_option("config", a.config, "Bake configuration (TOML)")->required();
  app.add_option("--store", a.store, "Geometry store (default: the configuration's)");
  app.add_option("--cells", a.cells, "Cells to sample (ordered serpentine over the grid)")->capture_default_str();
  app.add_option("--gops", a.gops, "Group sizes (frames from one keyframe)")->delimiter(',')->capture_default_str();
  app.add_option("--avif", a.avif, "AVIF qualities (the bake's encoder)")->delimiter(',')->capture_default_str();
  app.add_option("--av1-crf", a.av1_crf, "libaom-av1 cq levels (0..63; none: skip AV1)")->delimiter(',')->capture_default_str();
  app.add_option("--x265-crf", a.x265_crf, "libx265 crf values (0..51; none: skip HEVC)")->delimiter(',')->capture_default_str();
  app.add_option("--baseline-quality", a.baseline_quality, "AVIF quality whose PSNR the curves are compared at")
      ->capture_default_str();
  app.add_option("--aom-cpu-used", a.aom_cpu_used, "libaom-av1 cpu-used")->capture_default_str();
  app.add_option("--aom-usage", a.aom_usage, "libaom-av1 usage: good | realtime")->capture_default_str();
  app.add_option("--x265-preset", a.x265_preset, "libx265 preset")->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::exit(app.exit(e));
  }
  return a;
}

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// Rows along x, every other row (and layer) reversed: consecutive cells touch.
std::vector<CellSpec> serpentine(std::vector<CellSpec> cells) {
  std::sort(cells.begin(), cells.end(), [](const CellSpec& a, const CellSpec& b) {
    auto key = [](const CellSpec& c) {
      const int y = (c.gz % 2) ? -c.gy : c.gy;
      const int x = ((c.gy + c.gz) % 2) ? -c.gx : c.gx;
      return std::make_tuple(c.region, c.gz, y, x);
    };
    return key(a) < key(b);
  });
  return cells;
}

// What one quality point of one codec measured, per face (faces' order).
struct FaceResult {
  double bytes = 0;  // the face's share of its group's bytes
  double sq_error = 0, ssim = 0;
  double encode_ms = 0;  // its share of its group's encode
  double decode_ms = 0;  // random access: ready from its group's keyframe
};

struct Point {
  std::string codec;
  int gop = 1;
  double quality = 0;
  std::vector<FaceResult> faces;
};

struct Summary {
  double kb_face = 0, kb_cell = 0, psnr_pooled = 0, psnr_median = 0, psnr_worst = 0, ssim = 0, enc_ms = 0;
  double dec_mean = 0, dec_worst = 0, cell_dec_mean = 0, cell_dec_worst = 0;
};

Summary summarise(const Point& p, const std::vector<SampledFace>& faces) {
  Summary s;
  double se = 0, samples = 0;
  std::vector<double> face_psnr;
  std::map<std::int64_t, double> cell_bytes, cell_dec;
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const FaceResult& r = p.faces[i];
    const double n = 3.0 * double(faces[i].covered_count);
    se += r.sq_error, samples += n;
    face_psnr.push_back(psnr(r.sq_error, n));
    s.kb_face += r.bytes, s.ssim += r.ssim, s.enc_ms += r.encode_ms, s.dec_mean += r.decode_ms;
    s.dec_worst = std::max(s.dec_worst, r.decode_ms);
    cell_bytes[faces[i].cell.id] += r.bytes;
    cell_dec[faces[i].cell.id] += r.decode_ms;
  }
  const double k = double(faces.size());
  s.kb_face /= 1024 * k, s.ssim /= k, s.enc_ms /= k, s.dec_mean /= k;
  std::sort(face_psnr.begin(), face_psnr.end());
  s.psnr_pooled = psnr(se, samples);
  s.psnr_median = face_psnr[face_psnr.size() / 2];
  s.psnr_worst = face_psnr.front();
  for (const auto& [id, b] : cell_bytes) s.kb_cell += b;
  s.kb_cell /= 1024 * double(cell_bytes.size());
  for (const auto& [id, d] : cell_dec) s.cell_dec_mean += d, s.cell_dec_worst = std::max(s.cell_dec_worst, d);
  s.cell_dec_mean /= double(cell_dec.size());
  return s;
}

void print_header() {
  std::printf("%-12s %4s %6s %8s %8s %7s %7s %7s %7s %8s %8s %8s %9s %9s\n", "codec", "gop", "q", "KB/face",
              "KB/cell", "PSNR", "median", "worst", "SSIM", "enc ms", "dec ms", "dec max", "cell dec", "cell max");
}

void print_point(const Point& p, const Summary& s) {
  std::printf("%-12s %4d %6.0f %8.2f %8.1f %7.2f %7.2f %7.2f %7.4f %8.1f %8.2f %8.2f %9.1f %9.1f\n", p.codec.c_str(),
              p.gop, p.quality, s.kb_face, s.kb_cell, s.psnr_pooled, s.psnr_median, s.psnr_worst, s.ssim, s.enc_ms,
              s.dec_mean, s.dec_worst, s.cell_dec_mean, s.cell_dec_worst);
  std::fflush(stdout);
}

Point measure_avif(const std::vector<SampledFace>& faces, int quality) {
  Point p{"avif", 1, double(quality), {}};
  for (const SampledFace& f : faces) {
    FaceResult r;
    auto t0 = Clock::now();
    const std::vector<std::uint8_t> bytes = encode_image(f.color, f.size, f.size, {"avif", quality});
    r.encode_ms = ms_since(t0);
    t0 = Clock::now();
    const DecodedImage img = decode_image(bytes);
    r.decode_ms = ms_since(t0);
    r.bytes = double(bytes.size());
    r.sq_error = covered_sq_error(f, img.pixels);
    r.ssim = covered_ssim(f, img.pixels);
    p.faces.push_back(r);
  }
  return p;
}

// `sequences`: per face direction, indices into `faces` in serpentine order.
Point measure_video(const std::vector<SampledFace>& faces, const std::vector<std::vector<std::size_t>>& sequences,
                    const video::EncoderParams& params, const std::string& decoder, const std::string& label,
                    int gop) {
  Point p{label, gop, params.crf, std::vector<FaceResult>(faces.size())};
  const int size = faces.front().size;
  for (const std::vector<std::size_t>& seq : sequences)
    for (std::size_t g0 = 0; g0 < seq.size(); g0 += std::size_t(gop)) {
      const std::size_t g1 = std::min(seq.size(), g0 + std::size_t(gop));
      std::vector<const std::vector<Rgba8>*> frames;
      for (std::size_t j = g0; j < g1; ++j) frames.push_back(&faces[seq[j]].color);
      const video::EncodedGroup enc = video::encode_group(frames, size, params);
      const video::DecodedGroup dec = video::decode_group(enc, decoder, size);
      const double n = double(frames.size());
      for (std::size_t j = g0; j < g1; ++j) {
        const SampledFace& f = faces[seq[j]];
        FaceResult& r = p.faces[seq[j]];
        r.bytes = double(enc.bytes) / n;
        r.encode_ms = enc.encode_ms / n;
        r.decode_ms = dec.ready_ms[j - g0];
        r.sq_error = covered_sq_error(f, dec.frames[j - g0]);
        r.ssim = covered_ssim(f, dec.frames[j - g0]);
      }
    }
  return p;
}

// Bytes per face where the curve (points of one codec and GOP) reaches `db`,
// interpolating log(bytes) linearly in PSNR; < 0 outside the measured range.
double kb_at_psnr(std::vector<std::pair<double, double>> curve, double db) {
  std::sort(curve.begin(), curve.end());
  for (std::size_t i = 1; i < curve.size(); ++i) {
    const auto [p0, b0] = curve[i - 1];
    const auto [p1, b1] = curve[i];
    if (db >= p0 && db <= p1) {
      const double t = p1 > p0 ? (db - p0) / (p1 - p0) : 0;
      return std::exp(std::log(b0) + t * (std::log(b1) - std::log(b0)));
    }
  }
  return -1;
}

int run(int argc, char** argv) {
  const Args args = parse_args(argc, argv);
  if (!std::getenv("LP_NUM_THREADS")) setenv("LP_NUM_THREADS", "1", 1);
  av_log_set_level(AV_LOG_ERROR);
  BakeConfig config = load_bake_config(args.config);
  if (!args.store.empty()) config.store = args.store;
  const std::vector<CellSpec> cells =
      serpentine(select_cells(enumerate_cells(config.regions, config.cell_size), args.cells));
  const auto t_sample = Clock::now();
  const std::vector<SampledFace> faces = sample_centre_faces(config, cells);
  std::vector<std::vector<std::size_t>> sequences(kCubeFaces);
  for (std::size_t i = 0; i < faces.size(); ++i) sequences[std::size_t(faces[i].face)].push_back(i);
  std::size_t covered = 0;
  for (const SampledFace& f : faces) covered += f.covered_count;
  const int n = faces.front().size;
  std::printf("%zu cells in serpentine order:", cells.size());
  for (const CellSpec& c : cells) std::printf(" %lld", static_cast<long long>(c.id));
  std::printf("\n%zu faces of %d^2 with covered pixels (%.1f %% covered), sequences per direction:", faces.size(), n,
              100.0 * double(covered) / (double(faces.size()) * n * n));
  for (const auto& s : sequences) std::printf(" %zu", s.size());
  std::printf("; sampled in %.1f s\n", ms_since(t_sample) / 1000);
  {  // what the video path's colour conversion alone loses
    const video::ColourConverter to_yuv(n, true), to_rgb(n, false);
    double se = 0, samples = 0;
    for (const SampledFace& f : faces) {
      video::FramePtr fr = video::make_frame();
      fr->format = AV_PIX_FMT_YUV444P;
      fr->width = fr->height = n;
      video::check(av_frame_get_buffer(fr.get(), 0), "av_frame_get_buffer");
      to_yuv.to_yuv(f.color, *fr);
      se += covered_sq_error(f, to_rgb.to_rgba(*fr));
      samples += 3.0 * double(f.covered_count);
    }
    std::printf("RGB -> full-range BT.601 yuv444p -> RGB alone: %.2f dB on covered pixels\n", psnr(se, samples));
  }
  std::printf("av1: libaom-av1 usage=%s cpu-used=%d yuv444p, decoded by libdav1d; hevc: libx265 preset %s yuv444p, "
              "decoded by libavcodec hevc; one thread each\n",
              args.aom_usage.c_str(), args.aom_cpu_used, args.x265_preset.c_str());
  print_header();

  std::vector<Point> points;
  auto add = [&](Point p) {
    print_point(p, summarise(p, faces));
    points.push_back(std::move(p));
  };
  for (int q : args.avif) add(measure_avif(faces, q));
  for (int gop : args.gops) {
    if (gop < 1) throw std::invalid_argument("--gops: a group has at least 1 frame");
    for (double crf : args.av1_crf) {
      video::EncoderParams e;
      e.encoder = "libaom-av1", e.crf = crf, e.aom_cpu_used = args.aom_cpu_used, e.aom_usage = args.aom_usage;
      add(measure_video(faces, sequences, e, "libdav1d", "av1", gop));
    }
    for (double crf : args.x265_crf) {
      video::EncoderParams e;
      e.encoder = "libx265", e.crf = crf, e.x265_preset = args.x265_preset;
      add(measure_video(faces, sequences, e, "hevc", "hevc", gop));
    }
  }

  // Every curve at the baseline's PSNR.
  double base_db = -1, base_kb = 0;
  std::map<std::pair<std::string, int>, std::vector<std::pair<double, double>>> curves;
  for (const Point& p : points) {
    const Summary s = summarise(p, faces);
    curves[{p.codec, p.gop}].push_back({s.psnr_pooled, s.kb_face});
    if (p.codec == "avif" && int(p.quality) == args.baseline_quality) base_db = s.psnr_pooled, base_kb = s.kb_face;
  }
  if (base_db < 0) return 0;
  std::printf("\nat AVIF %d's PSNR (%.2f dB, %.2f KB/face):\n", args.baseline_quality, base_db, base_kb);
  for (const auto& [key, curve] : curves) {
    const double kb = kb_at_psnr(curve, base_db);
    if (kb < 0)
      std::printf("  %-5s gop %2d: outside the measured range\n", key.first.c_str(), key.second);
    else
      std::printf("  %-5s gop %2d: %6.2f KB/face (%+.0f %%)\n", key.first.c_str(), key.second, kb,
                  100 * (kb / base_kb - 1));
  }
  return 0;
}

}  // namespace
}  // namespace cellbake

int main(int argc, char** argv) {
  return cellbake::run_bench_program("bench_spatial_video", cellbake::run, argc, argv);
}
