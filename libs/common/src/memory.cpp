#include "concert/common/memory.hpp"

#include <malloc.h>

namespace concert {

bool fix_malloc_thresholds() {
  // Setting M_MMAP_THRESHOLD explicitly turns off glibc's dynamic adjustment of it (and of
  // M_TRIM_THRESHOLD); 128 KiB is glibc's own starting value.
  return mallopt(M_MMAP_THRESHOLD, 128 * 1024) == 1;
}

}  // namespace concert
