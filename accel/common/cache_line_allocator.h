// The allocator of the BVH node arrays: 64-byte aligned storage, so a binary sibling pair shares one cache
// line and an 8-wide node starts on one. Arrays of at least 2 MiB are mapped on transparent huge pages
// (huge_pages.h, as Embree's os_malloc). UninitializedAllocator leaves resize()'s elements unwritten, for
// large arrays filled in parallel (the BVH's leaf blocks, the spatial trees' leaf copies).
#pragma once

#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>

#include "accel/common/huge_pages.h"

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

/// CacheLineAllocator (64-byte aligned, huge pages from 2 MiB on) whose resize() default-initializes,
/// which for a trivial T leaves the memory untouched: the first write, and with it the page faults and the
/// kernel's zeroing, then happens in the parallel pass that fills the elements, not serially in the
/// resize (which would also write every byte once more).
template <class T>
struct UninitializedAllocator : CacheLineAllocator<T> {
  /// A stateless allocator.
  UninitializedAllocator() = default;
  /// Rebinding from another element type.
  template <class U>
  UninitializedAllocator(const UninitializedAllocator<U>&) {}
  /// Default-initializes *p (no write for a trivial U).
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  /// Constructs *p from args.
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

}  // namespace ab
