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
/// "Benchmark report") this took skirt's query time from 41.5 / 41.6 / 40.4 / 39.6 to 37.5 /
/// 34.2 / 39.2 / 35.0 ms per frame (four alternating runs; page faults about 67,000 -> 6,800)
/// and cloth-ball's from 48.1 / 45.6 to 43.8 / 42.0; bowl, funnel, breaking and a
/// 900,000-triangle scene of 5,000 blobs stayed within their run-to-run spread. Peak memory:
/// skirt 40 -> 42 MB, the blobs 1.18 -> 1.20 GB.
inline void keep_freed_memory_for_reuse() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
#endif
}

}  // namespace vproxq
