#include <mpm/core/huge_pages.h>

#include <sys/mman.h>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <cstdint>

namespace mpm {

void advise_huge_pages(void* p, std::size_t bytes) {
#ifdef MADV_HUGEPAGE
  constexpr std::uintptr_t huge = std::uintptr_t{1} << 21;
  const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(p) + huge - 1) & ~(huge - 1);
  const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(p) + bytes) & ~(huge - 1);
  if (p && end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)p;
  (void)bytes;
#endif
}

void keep_freed_memory() {
#if defined(__GLIBC__)
  constexpr int huge = 1 << 30;     // [B]: above any buffer a step allocates
  mallopt(M_MMAP_THRESHOLD, huge);  // also turns off the threshold's own adjustment
  mallopt(M_TRIM_THRESHOLD, huge);
#endif
}

}  // namespace mpm
