// The allocator of the BVH node arrays: 64-byte aligned storage, so a binary sibling pair shares one cache
// line and an 8-wide node starts on one.
#pragma once

#include <cstddef>
#include <new>

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
  /// Storage for n elements, 64-byte aligned.
  T* allocate(size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(64))); }
  /// Frees storage from allocate().
  void deallocate(T* p, size_t) { ::operator delete(p, std::align_val_t(64)); }
  /// Every instance can free every other's storage.
  bool operator==(const CacheLineAllocator&) const { return true; }
};

}  // namespace ab
