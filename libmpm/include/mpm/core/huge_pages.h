#pragma once
//! Advice to back a large, not yet touched buffer with transparent huge pages.
//!
//! The first touch of each page of fresh memory is a page fault; on a virtual machine a fault
//! costs microseconds, and a particle move, a checkpoint image or a freshly grown channel of a
//! million particles touches tens of thousands of 4 KiB pages. Where the kernel's transparent
//! huge pages are in "madvise" mode (Debian's default), advised ranges fault once per 2 MiB.
#include <cstddef>
#include <vector>

namespace mpm {

//! Advises the whole 2 MiB pages inside [p, p + bytes) (call it before the first touch); a
//! no-op where the advice is not supported. Never fails: it is only advice.
void advise_huge_pages(void* p, std::size_t bytes);

//! Makes `v` hold room for n elements, for a buffer about to be overwritten: when it has to
//! allocate anew it drops what `v` holds (nothing is copied) and advises the new room for huge
//! pages. resize() afterwards.
template <class T>
void reserve_advised(std::vector<T>& v, std::size_t n) {
  if (v.capacity() >= n) return;
  std::vector<T>().swap(v);
  v.reserve(n);
  advise_huge_pages(v.data(), n * sizeof(T));
}

//! Keeps the memory this process frees for its next allocations instead of handing it back to
//! the kernel (glibc: blocks of any size come from the heap rather than from their own
//! mappings, and the heap is not trimmed), so that work buffers allocated anew every step (the
//! adaptive grid's set-up: tables of tens of MB) land on pages already mapped instead of
//! faulting in fresh zeroed ones. The price is resident memory: what was once held stays held.
//! The apps call it at start-up (run_app); a no-op outside glibc.
void keep_freed_memory();

}  // namespace mpm
