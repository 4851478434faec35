// How a process that runs jobs and then ends uses glibc's allocator (decision 52): the
// command-line tool, and the scale bench's children that stand for it.
#pragma once

#include <malloc.h>

#include <limits>

namespace mdn::service {

// Every stage allocates its arrays and frees them; glibc serves the large ones from fresh
// mmap()s and unmaps them on free, so the next stage faults as many pages in again (307,000
// faults for a 1.2M-face run whose peak is 146,000 pages). From the heap only, never trimmed, a
// freed array is the next stage's memory. Not for a long-lived process (the server): nothing
// is given back until it ends.
inline void keep_freed_memory() {
  ::mallopt(M_MMAP_MAX, 0);
  ::mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
}

}  // namespace mdn::service
