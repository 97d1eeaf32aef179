#include "pipeline/bake_estimate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace cellbake {

namespace {

// (T / 2 M) raised to `below` for smaller models and `above` for larger ones.
double model_size_factor(std::uint64_t model_triangles, double below, double above) {
  if (model_triangles == 0) return 1.0;
  const double ratio = double(model_triangles) / kMeasuredModelTriangles;
  return std::pow(ratio, ratio <= 1.0 ? below : above);
}

}  // namespace

BakeEstimate estimate_bake(std::uint64_t cells, int face_size, int threads, std::uint64_t model_triangles) {
  const double pixels = (double(face_size) / 512.0) * (double(face_size) / 512.0);
  BakeEstimate e;
  e.core_seconds_per_cell =
      kMeasuredCoreSecondsPerCell * pixels * model_size_factor(model_triangles, 0.25, 0.5);
  e.seconds = e.core_seconds_per_cell * double(cells) / double(std::max(1, threads));
  e.bytes_per_cell =
      kMeasuredBytesPerCell * pixels * std::max(0.05, model_size_factor(model_triangles, 0.5, 0.9));
  e.bytes = e.bytes_per_cell * double(cells);
  return e;
}

std::string duration_text(double s) {
  char buf[64];
  if (s < 90)
    std::snprintf(buf, sizeof buf, "%.0f s", s);
  else if (s < 5400)
    std::snprintf(buf, sizeof buf, "%.0f min", s / 60);
  else
    std::snprintf(buf, sizeof buf, "%.1f h", s / 3600);
  return buf;
}

}  // namespace cellbake
