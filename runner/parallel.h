// TBB adapters handed to pipeline code that must not know TBB itself.
#pragma once

#include "pipeline/ingest.h"

namespace cellbake {

// A ParallelFor over oneTBB's work-stealing scheduler (deterministic results
// as long as fn(i) writes only slot i).
ParallelFor tbb_parallel_for();

}  // namespace cellbake
