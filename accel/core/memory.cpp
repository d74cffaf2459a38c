// The replaced global operator new and delete of memory.h. Every block is a malloc block (aligned ones from
// aligned_alloc), so delete can learn its size from malloc_usable_size without a header of its own, and the
// new/delete pairs keep working with any mix of sized, unsized and aligned forms.
#include "accel/core/memory.h"

#include <malloc.h>

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(memory_sanitizer) || __has_feature(thread_sanitizer)
#define AB_NO_HEAP_ACCOUNTING 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define AB_NO_HEAP_ACCOUNTING 1
#endif

namespace ab {
namespace {

std::atomic<uint64_t> g_in_use{0};
std::atomic<uint64_t> g_peak{0};

[[maybe_unused]] void count_alloc(void* p) {
  const uint64_t size = malloc_usable_size(p);
  const uint64_t now = g_in_use.fetch_add(size, std::memory_order_relaxed) + size;
  uint64_t peak = g_peak.load(std::memory_order_relaxed);
  while (now > peak && !g_peak.compare_exchange_weak(peak, now, std::memory_order_relaxed)) {
  }
}

[[maybe_unused]] void count_free(void* p) {
  if (p) g_in_use.fetch_sub(malloc_usable_size(p), std::memory_order_relaxed);
}

}  // namespace

uint64_t heap_bytes_in_use() {
  return g_in_use.load(std::memory_order_relaxed);
}

bool heap_accounting_enabled() {
#ifdef AB_NO_HEAP_ACCOUNTING
  return false;
#else
  return true;
#endif
}

HeapPeak::HeapPeak() : start_(heap_bytes_in_use()) {
  g_peak.store(start_, std::memory_order_relaxed);
}

uint64_t HeapPeak::bytes() const {
  const uint64_t peak = g_peak.load(std::memory_order_relaxed);
  return peak > start_ ? peak - start_ : 0;
}

}  // namespace ab

#ifndef AB_NO_HEAP_ACCOUNTING

namespace {

void* allocate(std::size_t size, std::size_t align, bool nothrow) {
  if (size == 0) size = 1;
  for (;;) {
    void* p = align <= alignof(std::max_align_t)
                  ? std::malloc(size)
                  : std::aligned_alloc(align, (size + align - 1) / align * align);
    if (p) {
      ab::count_alloc(p);
      return p;
    }
    std::new_handler handler = std::get_new_handler();
    if (!handler) {
      if (nothrow) return nullptr;
      throw std::bad_alloc();
    }
    handler();
  }
}

void release(void* p) noexcept {
  ab::count_free(p);
  std::free(p);
}

constexpr std::size_t kPlain = alignof(std::max_align_t);

}  // namespace

void* operator new(std::size_t n) {
  return allocate(n, kPlain, false);
}
void* operator new[](std::size_t n) {
  return allocate(n, kPlain, false);
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  return allocate(n, kPlain, true);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  return allocate(n, kPlain, true);
}
void* operator new(std::size_t n, std::align_val_t a) {
  return allocate(n, std::size_t(a), false);
}
void* operator new[](std::size_t n, std::align_val_t a) {
  return allocate(n, std::size_t(a), false);
}
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocate(n, std::size_t(a), true);
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return allocate(n, std::size_t(a), true);
}
void operator delete(void* p) noexcept {
  release(p);
}
void operator delete[](void* p) noexcept {
  release(p);
}
void operator delete(void* p, std::size_t) noexcept {
  release(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  release(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  release(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  release(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  release(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  release(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  release(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  release(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  release(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  release(p);
}

#endif
