// TBB adapters handed to pipeline code that must not know TBB itself.
#pragma once

#include "pipeline/ingest.h"

namespace cellbake {

// A ParallelFor over oneTBB's work-stealing scheduler (deterministic results
// as long as fn(i) writes only slot i).
ParallelFor tbb_parallel_for();

// The worker threads a command runs: `requested` when positive, else one per
// hardware thread (at least one).
int worker_threads(int requested);

// worker_threads(requested) for commands whose workers draw (bake, verify):
// several single-threaded llvmpipe contexts use the cores better than one
// multi-threaded one (measured on the 2-core project machine), so unless the
// user set LP_NUM_THREADS it is set to 1 when several workers draw, 2 for one.
int drawing_worker_threads(int requested);

}  // namespace cellbake
