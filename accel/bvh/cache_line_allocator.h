// The allocator of the BVH node arrays: 64-byte aligned storage, so a binary sibling pair shares one cache
// line and an 8-wide node starts on one. Arrays of at least 2 MiB are mapped on transparent huge pages
// (huge_pages.h, as Embree's os_malloc).
#pragma once

#include <cstddef>
#include <new>

#include "accel/bvh/huge_pages.h"

namespace ab {

/// Allocator aligning every allocation to 64 bytes (a cache line).
template <class T>
struct CacheLineAllocator {
  using value_type = T;  ///< the element type
  /// A stateless allocator.
  CacheLineAllocator() = default;
  /// Rebinding from another element type.
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) {}
  /// Storage for n elements, 64-byte aligned (on huge pages from kHugePageBytes on).
  T* allocate(size_t n) {
    if (n * sizeof(T) >= kHugePageBytes) return static_cast<T*>(map_huge_pages(n * sizeof(T)));
    return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(64)));
  }
  /// Frees storage from allocate(n).
  void deallocate(T* p, size_t n) {
    if (n * sizeof(T) >= kHugePageBytes) return unmap_huge_pages(p, n * sizeof(T));
    ::operator delete(p, std::align_val_t(64));
  }
  /// Every instance can free every other's storage.
  bool operator==(const CacheLineAllocator&) const { return true; }
};

}  // namespace ab
