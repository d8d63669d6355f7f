#include "neraf/util/heap.h"

#include <malloc.h>

namespace neraf::util {

void keep_freed_memory_in_heap() {
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

}  // namespace neraf::util
