#pragma once
// How the structure's programs keep freed memory (called once, first thing in main).
//
// Why. A co-rotational step assembles, reorders and factorizes sparse matrices of a few hundred kB at every
// Newton iteration and frees them again. glibc hands freed memory at the top of its heap back to the system
// once more than its trim threshold lies free there, and the next iteration's allocation then faults the
// same pages back in, one by one. Whether that happens depends on the order of allocations, not on the work:
// a change that added one vector product per step turned it on for the 1000-element co-rotational
// cantilever of sphfsi-structure-bench (212,000 page faults for the benchmark against 5,400 before; 11.5 ms
// a step against 10.3 ms, docs/benchmarks.md). Keeping up to 256 MiB of freed memory and serving blocks
// below 32 MiB from the heap removes it in every build: 1,400 page faults and 8.9 ms. The price is memory the
// process holds after a peak, bounded by that threshold; a beam model needs far less.
namespace sphfsi::structure {

void keep_freed_memory();

}  // namespace sphfsi::structure
