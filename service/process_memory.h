// How a process that runs jobs and then ends uses glibc's allocator (decisions 52 and 100): the
// command-line tool, and the scale bench's children that stand for it.
#pragma once

#include <malloc.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

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

// Decision 100: from this much input on, the command-line tool runs with transparent huge pages
// for its heap (glibc's `glibc.malloc.hugetlb=1`: 2 MiB pages where the kernel allows them on
// request), so that its first touches fault a 512th as often. Below it a run's heap is a few
// MiB and the restart it takes (the tunable is read only at start-up) is not worth it.
inline constexpr std::uintmax_t kHugePagesMinInputBytes = std::uintmax_t{4} << 20;

// GLIBC_TUNABLES with glibc.malloc.hugetlb=1 added to `current` (the variable's value, null if
// unset), or nothing if `current` already sets glibc.malloc.hugetlb (to anything: the caller's
// choice stands, and a restarted process does not restart again).
inline std::optional<std::string> tunables_with_huge_pages(const char* current) {
  const std::string_view now = current ? current : "";
  if (now.find("glibc.malloc.hugetlb=") != std::string_view::npos) return std::nullopt;
  std::string out(now);
  if (!out.empty()) out += ':';
  out += "glibc.malloc.hugetlb=1";
  return out;
}

// Whether the kernel gives huge pages on request: /sys/kernel/mm/transparent_hugepage/enabled's
// `text` selects [always] or [madvise], not [never] (an unreadable file: no).
inline bool huge_pages_on_request(std::string_view text) {
  return text.find("[always]") != std::string_view::npos || text.find("[madvise]") != std::string_view::npos;
}
// The same, of this machine's kernel.
inline bool kernel_gives_huge_pages_on_request() {
  std::ifstream file("/sys/kernel/mm/transparent_hugepage/enabled");
  return huge_pages_on_request(std::string(std::istreambuf_iterator<char>(file), {}));
}

}  // namespace mdn::service
