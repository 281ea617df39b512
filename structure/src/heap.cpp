#include "sphfsi/structure/heap.hpp"

#include <cstdlib>  // defines __GLIBC__ where the C library is glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace sphfsi::structure {

void keep_freed_memory() {
#if defined(__GLIBC__)
    // Fixed thresholds also turn off glibc's own adjustment of them (mallopt(3)).
    mallopt(M_TRIM_THRESHOLD, 256 << 20);
    mallopt(M_MMAP_THRESHOLD, 32 << 20);
#endif
}

}  // namespace sphfsi::structure
