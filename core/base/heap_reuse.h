// Freed memory kept by the allocator for the next allocation instead of returned to the system.
// On these machines (virtualised, 2 cores) a page fault costs ~10 us: reading a 50 MB recorded
// frame into fresh memory took 450-630 ms, into reused memory 34-41 ms (median of 8 frames each,
// render/frame_store.h). The workbench decodes a frame per timeline jump and drops others, so it
// keeps what it frees: allocations up to 32 MB (glibc's largest mmap threshold) come from the
// heap, and up to 1 GB of free heap is kept. The decoded frames' cap bounds what is held.
#pragma once

#include <malloc.h>

namespace freqlab {

// Returns false when the allocator refused (another libc: nothing changes).
inline bool keep_freed_memory_for_reuse() {
#ifdef M_MMAP_THRESHOLD
    return mallopt(M_MMAP_THRESHOLD, 32 << 20) == 1 && mallopt(M_TRIM_THRESHOLD, 1 << 30) == 1;
#else
    return false;
#endif
}

}  // namespace freqlab
