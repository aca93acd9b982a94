// Large arrays backed by transparent huge pages where Linux offers them (madvise mode).
//
// Why: a stage that allocates a few hundred bytes per vertex of fresh memory spends a large
// share of its time in page faults (one per 4 KiB, each charged, zeroed and mapped under the
// process's memory lock); 2 MiB pages take 512 times fewer. Measured on the curvature stage
// (docs/benchmarks.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace ncrev::detail {

/// Sizes `v` to `n` value-initialised elements, asking for huge pages before the first touch.
template <class T, class A>
void resize_huge(std::vector<T, A>& v, std::size_t n) {
    v.clear();
    v.reserve(n);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
    const auto b = reinterpret_cast<std::uintptr_t>(v.data());
    const std::uintptr_t lo = (b + kHuge - 1) & ~(kHuge - 1);
    const std::uintptr_t hi = (b + n * sizeof(T)) & ~(kHuge - 1);
    if (hi > lo) ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
#endif
    v.resize(n);
}

}  // namespace ncrev::detail
