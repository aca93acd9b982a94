// Exact weld: maps points with bit-identical coordinates to one class, classes numbered by
// first occurrence. Shared by the STL reader (float32 keys, welding while it reads) and mesh
// building (float64 keys). Internal header.
//
// One ordered pass over an open-addressing table of (hash tag, class) slots. Input order
// matters for speed: a vertex recurs a few rows of facets later, so a tagged direct-mapped
// cache of recent classes answers most lookups from L2, and the large table is prefetched a
// few points ahead for the rest. (A hash-partitioned parallel weld was measured 5x slower on
// 2 cores: it scatters the accesses to the points.)
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "detail/huge_pages.h"

namespace ncrev::detail {

/// Word = std::uint32_t for float32 coordinates, std::uint64_t for float64. Keys are the
/// coordinates' bit patterns; the caller maps -0 to +0 first.
template <class Word>
class ExactWelder {
   public:
    using Key = std::array<Word, 3>;
    static constexpr std::uint32_t kNone = 0xFFFFFFFFu;

    /// `expected_points`: how many points will be inserted (sizes the table: a facet soup
    /// holds each vertex about six times: a table of half the points is at most a third full and
    /// never grows; other inputs grow it at half load).
    explicit ExactWelder(std::size_t expected_points)
        : cap_(std::bit_ceil(std::max<std::size_t>(1024, expected_points / 2))),
          recent_(kRecent, 0) {
        allocate_table(table_, cap_);
        // A facet soup's vertices are about a sixth of its points; room for a quarter.
        reserve_huge(keys_, expected_points / 4);
    }

    static bool same(const Key& a, const Key& b) {
        // Word by word: std::array's operator== becomes a memcmp call here.
        return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
    }

    static std::uint64_t hash(const Key& k) {
        std::uint64_t h = std::uint64_t{k[0]} * 0x9E3779B97F4A7C15ull;
        h ^= std::rotl(std::uint64_t{k[1]} * 0xC2B2AE3D27D4EB4Full, 21);
        h ^= std::rotl(std::uint64_t{k[2]} * 0x165667B19E3779F9ull, 42);
        h ^= h >> 29;
        h *= 0xBF58476D1CE4E5B9ull;
        h ^= h >> 32;
        return h;
    }

    /// Hints the table slot of a key that will be inserted soon.
    void prefetch(const Key& k) const { __builtin_prefetch(&table_[hash(k) & (cap_ - 1)]); }

    /// The class of `k`, a new one (numbered in order) if it was never seen.
    std::uint32_t insert(const Key& k) {
        const std::uint64_t h = hash(k);
        const auto tag = static_cast<std::uint32_t>(h >> 32);
        std::uint64_t& hint = recent_[(h >> 17) & (kRecent - 1)];
        if (hint != 0 && static_cast<std::uint32_t>(hint >> 32) == tag) {
            const auto c = static_cast<std::uint32_t>(hint) - 1;
            if (same(keys_[c], k)) return c;
        }
        std::size_t mask = cap_ - 1;
        std::size_t s = h & mask;
        while (table_[s] != 0) {
            const std::uint64_t entry = table_[s];
            if (static_cast<std::uint32_t>(entry >> 32) == tag) {
                const auto c = static_cast<std::uint32_t>(entry) - 1;
                if (same(keys_[c], k)) {
                    hint = entry;
                    return c;
                }
            }
            s = (s + 1) & mask;
        }
        const auto c = static_cast<std::uint32_t>(keys_.size());
        if (keys_.size() == keys_.capacity()) reserve_huge(keys_, 2 * keys_.size() + 1024);
        keys_.push_back(k);
        const std::uint64_t entry = (std::uint64_t{tag} << 32) | (c + 1);
        table_[s] = entry;
        hint = entry;
        if (2 * keys_.size() > cap_) grow();
        return c;
    }

    const std::vector<Key>& keys() const { return keys_; }
    std::size_t size() const { return keys_.size(); }

   private:
    // 32768 tagged entries x 8 bytes = 256 KiB: fits L2, and keeps ~90% of entries alive across
    // the few thousand points between a vertex's recurrences in a facet-ordered file.
    static constexpr std::size_t kRecent = std::size_t{1} << 15;

    // Probing a large table misses the TLB on almost every new vertex (4 KiB pages cover a
    // 64 MiB table with 16384 entries); on Linux, ask for transparent huge pages first.
    static void allocate_table(std::vector<std::uint64_t>& t, std::size_t n) {
        resize_huge(t, n);  // zero-filled
    }

    void grow() {
        cap_ *= 2;
        const std::size_t mask = cap_ - 1;
        std::vector<std::uint64_t> bigger;
        allocate_table(bigger, cap_);
        for (std::uint32_t c = 0; c < keys_.size(); ++c) {
            const std::uint64_t h = hash(keys_[c]);
            std::size_t s = h & mask;
            while (bigger[s] != 0) s = (s + 1) & mask;
            bigger[s] = ((h >> 32) << 32) | (c + 1);
        }
        table_.swap(bigger);
    }

    std::size_t cap_;
    std::vector<std::uint64_t> table_;  // (hash tag << 32) | (class + 1); 0 = empty
    std::vector<std::uint64_t> recent_;
    std::vector<Key> keys_;
};

}  // namespace ncrev::detail
