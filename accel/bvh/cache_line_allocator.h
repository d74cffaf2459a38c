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
  T* allocate(size_t n) { return static_cast<T*>(allocate_large(n * sizeof(T))); }
  /// Frees storage from allocate(n).
  void deallocate(T* p, size_t n) { free_large(p, n * sizeof(T)); }
  /// Every instance can free every other's storage.
  bool operator==(const CacheLineAllocator&) const { return true; }
};

}  // namespace ab
