// Large arrays backed by transparent huge pages where Linux offers them (madvise mode).
//
// Why: a stage that allocates a few hundred bytes per vertex of fresh memory spends a large
// share of its time in page faults (one per 4 KiB, each charged, zeroed and mapped under the
// process's memory lock); 2 MiB pages take 512 times fewer. Measured on the curvature stage
// and on reading and building a mesh (docs/benchmarks.md). Arrays under 2 MiB are left alone:
// only whole 2 MiB pages inside an allocation are advised.
#pragma once

#include <cstddef>
#include <cstdint>
#include <iterator>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace ncrev::detail {

/// Asks for huge pages over the whole 2 MiB pages inside [p, p + bytes), before they are
/// first touched (pages already touched keep their 4 KiB pages).
inline void advise_huge([[maybe_unused]] const void* p, [[maybe_unused]] std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    constexpr std::uintptr_t kHuge = std::uintptr_t{2} << 20;
    const auto b = reinterpret_cast<std::uintptr_t>(p);
    const std::uintptr_t lo = (b + kHuge - 1) & ~(kHuge - 1);
    const std::uintptr_t hi = (b + bytes) & ~(kHuge - 1);
    if (hi > lo) ::madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
#endif
}

/// Reserves room for `n` elements in `v`, on huge pages: a new buffer is advised before the
/// elements move into it.
template <class T, class A>
void reserve_huge(std::vector<T, A>& v, std::size_t n) {
    if (n <= v.capacity()) return;
    std::vector<T, A> room(v.get_allocator());
    room.reserve(n);
    advise_huge(room.data(), room.capacity() * sizeof(T));
    room.insert(room.end(), std::make_move_iterator(v.begin()), std::make_move_iterator(v.end()));
    v.swap(room);
}

/// Sizes `v` to `n` value-initialised elements, asking for huge pages before the first touch.
template <class T, class A>
void resize_huge(std::vector<T, A>& v, std::size_t n) {
    v.clear();
    reserve_huge(v, n);
    v.resize(n);
}

/// Sizes `v` to `n` copies of `value`, asking for huge pages before the first touch.
template <class T, class A>
void assign_huge(std::vector<T, A>& v, std::size_t n, const T& value) {
    const T copy = value;  // `value` may be an element of `v`
    v.clear();
    reserve_huge(v, n);
    v.assign(n, copy);
}

}  // namespace ncrev::detail
