// Heap accounting for the peak memory of each build (BuildStats::peak_bytes): memory.cpp replaces the global
// operator new and delete, which then count the bytes the C++ heap holds (malloc_usable_size of every block,
// so the allocator's rounding is included) and their high-water mark. What it does not see: memory taken by
// malloc, mmap or an allocator of its own without going through operator new (Embree's BVH, which reports
// through its memory monitor instead; TBB's internal pools; the C libraries), and the stacks. It counts the
// whole process: allocations of other threads during a build (the harness builds one structure at a time) are
// in the peak too. In builds with AddressSanitizer the sanitizer keeps its own operator new, and the counts
// stay zero.
#pragma once

#include <cstdint>

namespace ab {

/// Bytes of the blocks operator new currently holds (0 when the accounting is off, see above).
uint64_t heap_bytes_in_use();

/// True when operator new is counted (false in sanitizer builds).
bool heap_accounting_enabled();

/// The heap's high-water mark over a scope: from construction, the most the heap held above what it held
/// then. One scope at a time (a nested or concurrent one restarts the process-wide mark).
class HeapPeak {
 public:
  /// Starts the scope (resets the process-wide mark to the current use).
  HeapPeak();
  /// The most bytes held above the start so far.
  uint64_t bytes() const;

 private:
  uint64_t start_;
};

}  // namespace ab
