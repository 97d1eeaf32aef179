// Viewer-side decode time of whole cells on one core: for each done cell of a
// cell database, decodes every face image and face mesh of its samples (what
// viewer/decoded_cell does before upload) and prints the median and worst
// milliseconds per cell and per sample, with the bytes by kind.
//
//   bench_cell_decode /tmp/h2/cmp2/new.db [--repeat 5]
//
// Not a Google Benchmark program: it reads a database.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/bench_program.h"
#include "stages/encode.h"
#include "storage/cell_db.h"

namespace cellbake {
namespace {

using Clock = std::chrono::steady_clock;

int run(int argc, char** argv) {
  if (argc < 2) throw std::invalid_argument("usage: bench_cell_decode CELLS.db [--repeat R]");
  const int repeat = argc >= 4 && std::string(argv[2]) == "--repeat" ? std::max(1, std::atoi(argv[3])) : 5;
  const CellDb db(argv[1], CellDb::Mode::read_only);
  std::vector<double> per_cell, per_sample;
  std::uint64_t colour = 0, mesh = 0;
  for (std::int64_t id : db.cell_ids()) {
    const std::optional<CellRow> row = db.get_cell(id);
    if (!row || row->status != "done" || row->samples.empty()) continue;
    double best = 1e300;
    for (int r = 0; r < repeat; ++r) {
      const auto t0 = Clock::now();
      std::size_t sink = 0;
      for (const SampleRow& s : row->samples)
        for (const FaceRow& f : s.faces)
          sink += decode_image(f.image).pixels.size() + decode_face_mesh(f.mesh).positions.size();
      best = std::min(best, std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      if (sink == 0) std::printf(" ");
    }
    per_cell.push_back(best);
    per_sample.push_back(best / double(row->samples.size()));
    for (const SampleRow& s : row->samples)
      for (const FaceRow& f : s.faces) colour += f.image.size(), mesh += f.mesh.size();
  }
  if (per_cell.empty()) throw std::runtime_error("no done cells");
  std::sort(per_cell.begin(), per_cell.end());
  std::sort(per_sample.begin(), per_sample.end());
  std::printf("%zu cells: decode ms per cell median %.2f, worst %.2f; per sample median %.2f, worst %.2f; "
              "per cell %.1f KB colour, %.1f KB mesh\n",
              per_cell.size(), per_cell[per_cell.size() / 2], per_cell.back(), per_sample[per_sample.size() / 2],
              per_sample.back(), colour / 1024.0 / double(per_cell.size()), mesh / 1024.0 / double(per_cell.size()));
  return 0;
}

}  // namespace
}  // namespace cellbake

int main(int argc, char** argv) {
  return cellbake::run_bench_program("bench_cell_decode", cellbake::run, argc, argv);
}
