#include "runner/heap_tuning.h"

#include <malloc.h>

namespace cellbake {

void keep_large_blocks_in_the_heap() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
}

}  // namespace cellbake
