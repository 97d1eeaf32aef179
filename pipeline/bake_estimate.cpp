#include "pipeline/bake_estimate.h"

#include <algorithm>
#include <cstdio>

namespace cellbake {

BakeEstimate estimate_bake(std::uint64_t cells, int face_size, int threads) {
  const double pixels = (double(face_size) / 512.0) * (double(face_size) / 512.0);
  BakeEstimate e;
  e.core_seconds_per_cell = kMeasuredCoreSecondsPerCell * pixels;
  e.seconds = e.core_seconds_per_cell * double(cells) / double(std::max(1, threads));
  e.bytes_per_cell = kMeasuredBytesPerCell * pixels;
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
