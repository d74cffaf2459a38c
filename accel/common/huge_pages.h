// Large build arrays on transparent huge pages. A build writes every byte of its large arrays (references,
// node slots, nodes, leaf blocks) once, so most of the cost of fresh memory is the page faults; with 2 MiB
// pages a 64 MB array takes 32 faults instead of 16,384. This is what Embree's os_malloc does
// (common/sys/alloc.cpp: madvise(MADV_HUGEPAGE) on allocations of at least 2 MiB).
#pragma once

#include <sys/mman.h>

#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>

namespace ab {

/// Allocations of at least this many bytes are mapped on their own and advised as huge pages.
inline constexpr size_t kHugePageBytes = size_t(2) << 20;

/// Bytes mapped for an allocation of `bytes` (at least kHugePageBytes): whole huge pages.
inline size_t huge_mapping_bytes(size_t bytes) {
  return (bytes + kHugePageBytes - 1) & ~(kHugePageBytes - 1);
}

/// Uninitialized storage of `bytes` (at least kHugePageBytes), aligned to a huge page and advised as
/// transparent huge pages (the advice is only a hint: without it the pages are ordinary ones). It comes from
/// the aligned operator new, so the heap accounting of accel/core/memory.h counts it. Throws std::bad_alloc.
inline void* map_huge_pages(size_t bytes) {
  const size_t mapped = huge_mapping_bytes(bytes);
  void* p = ::operator new(mapped, std::align_val_t(kHugePageBytes));
#ifdef MADV_HUGEPAGE
  madvise(p, mapped, MADV_HUGEPAGE);
#endif
  return p;
}

/// Frees storage from map_huge_pages(bytes).
inline void unmap_huge_pages(void* p, size_t) {
  ::operator delete(p, std::align_val_t(kHugePageBytes));
}

/// Uninitialized storage of `bytes`: on huge pages (map_huge_pages) from kHugePageBytes on, else 64-byte
/// aligned from new. The one allocation rule of LargeArray and CacheLineAllocator.
inline void* allocate_large(size_t bytes) {
  if (bytes >= kHugePageBytes) return map_huge_pages(bytes);
  return ::operator new(bytes, std::align_val_t(64));
}

/// Frees storage from allocate_large(bytes) (p may be null).
inline void free_large(void* p, size_t bytes) {
  if (p == nullptr) return;
  if (bytes >= kHugePageBytes) return unmap_huge_pages(p, bytes);
  ::operator delete(p, std::align_val_t(64));
}

/// A fixed-size array of trivially copyable T whose elements are not initialized (each is written before
/// it is read); at least kHugePageBytes of them are mapped on huge pages, smaller ones come from new.
template <class T>
class LargeArray {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  /// No storage.
  LargeArray() = default;
  /// Room for n elements, uninitialized.
  explicit LargeArray(size_t n) : size_(n), data_(static_cast<T*>(allocate_large(n * sizeof(T)))) {}
  LargeArray(LargeArray&& o) noexcept : size_(o.size_), data_(o.data_) { o.size_ = 0, o.data_ = nullptr; }
  LargeArray& operator=(LargeArray&& o) noexcept {
    std::swap(size_, o.size_);
    std::swap(data_, o.data_);
    return *this;
  }
  ~LargeArray() { free_large(data_, size_ * sizeof(T)); }

  /// The elements.
  T* get() const { return data_; }
  /// Element i.
  T& operator[](size_t i) const { return data_[i]; }
  /// Number of elements.
  size_t size() const { return size_; }

 private:
  size_t size_ = 0;
  T* data_ = nullptr;
};

}  // namespace ab
