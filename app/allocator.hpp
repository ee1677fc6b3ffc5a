#pragma once
// Allocator settings for a batch run, called first thing in main() (glibc; elsewhere nothing).
#include <cstdlib>  // defines __GLIBC__ on glibc
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace vproxq {

/// Keeps the memory that a frame frees for the next frame, instead of handing it back to the
/// kernel and taking it again, page fault by page fault. glibc serves a block above its mmap
/// threshold (128 KB at first, raised to the largest such block freed so far, at most 32 MB)
/// by mapping fresh pages, and gives the free memory at the top of a heap back once it exceeds
/// the trim threshold (twice the mmap threshold); every frame and CCD step allocates and frees
/// per-triangle tables of some MB (boxes, swept triangles, hierarchies), so each one faulted
/// their pages in again. Blocks up to 32 MB now come from the heap, and a heap keeps up to
/// 256 MB free at its top. On the report scenes (40 frames, all queries, 2 threads; README,
/// "Benchmark report") this took skirt from 42.3 to 34.8 ms per frame and cloth-ball from
/// 49.5 / 45.9 to 44.1 / 40.1, bowl, funnel, breaking and a 900,000-triangle scene of 5,000
/// blobs within their run-to-run spread; peak memory 41.5 -> 43.0 MB (skirt), 1.18 -> 1.20 GB
/// (the blobs).
inline void keep_freed_memory_for_reuse() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
#endif
}

}  // namespace vproxq
