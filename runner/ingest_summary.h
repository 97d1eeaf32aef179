// Console output for ingest: a progress callback and the closing summary.
#pragma once

#include <string>

#include "pipeline/ingest.h"

namespace cellbake {

// A ProgressCallback that prints phase changes and write progress to stderr.
ProgressCallback ingest_progress();

// Prints the ingest summary (counts, skips, chunks, bounds, timings, throughput).
void print_ingest_summary(const IngestReport& r, const std::string& store);

}  // namespace cellbake
