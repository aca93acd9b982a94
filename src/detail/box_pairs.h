// Every two of many small boxes that meet: a mesh's facets whose boxes touch, for the check of
// a mesh passing through itself (detail/self_intersection.h). The boxes, sorted along a Morton
// curve of their centres, go eight at a time into the leaves of a complete binary tree of
// single-precision boxes, and the tree is searched against itself. It keeps about 45 bytes a
// box (the double-precision TriangleTree, with its copy of each triangle, takes some 200): the
// search runs on every mesh healing builds, up to millions of facets.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <utility>
#include <vector>

#include "detail/huge_pages.h"
#include "ncrev/common.h"

namespace ncrev::detail {

/// The lower corner rounded down and the upper up to single precision: the box holds the
/// double-precision one it came from. An empty box (min above max) meets nothing.
struct FloatBox {
    std::array<float, 3> min{std::numeric_limits<float>::infinity(),
                             std::numeric_limits<float>::infinity(),
                             std::numeric_limits<float>::infinity()};
    std::array<float, 3> max{-std::numeric_limits<float>::infinity(),
                             -std::numeric_limits<float>::infinity(),
                             -std::numeric_limits<float>::infinity()};

    static float down(double x) {
        const auto f = static_cast<float>(x);
        return static_cast<double>(f) > x
                   ? std::nextafter(f, -std::numeric_limits<float>::infinity())
                   : f;
    }
    static float up(double x) {
        const auto f = static_cast<float>(x);
        return static_cast<double>(f) < x
                   ? std::nextafter(f, std::numeric_limits<float>::infinity())
                   : f;
    }
    static FloatBox of(const Box3& b) {
        FloatBox out;
        for (int k = 0; k < 3; ++k) {
            out.min[k] = down(b.min[k]);
            out.max[k] = up(b.max[k]);
        }
        return out;
    }
    void add(const FloatBox& b) {
        for (int k = 0; k < 3; ++k) {
            min[k] = std::min(min[k], b.min[k]);
            max[k] = std::max(max[k], b.max[k]);
        }
    }
    bool empty() const { return !(min[0] <= max[0]); }
    bool meets(const FloatBox& b) const {
        return min[0] <= b.max[0] && b.min[0] <= max[0] && min[1] <= b.max[1] &&
               b.min[1] <= max[1] && min[2] <= b.max[2] && b.min[2] <= max[2];
    }
};

/// x's low 21 bits spread to every third bit (bit k to bit 3k): three of them interleaved make
/// a 63-bit Morton code.
inline std::uint64_t spread_bits(std::uint64_t x) {
    x &= 0x1fffffu;
    x = (x | x << 32) & 0x1f00000000ffffu;
    x = (x | x << 16) & 0x1f0000ff0000ffu;
    x = (x | x << 8) & 0x100f00f00f00f00fu;
    x = (x | x << 4) & 0x10c30c30c30c30c3u;
    x = (x | x << 2) & 0x1249249249249249u;
    return x;
}

class BoxPairs {
   public:
    /// Boxes 0 … n - 1, `box(i)` the i-th (a Box3, called a few times for each), each grown by
    /// `grow` on every side. The same tree on any thread count.
    template <class BoxOf>
    BoxPairs(std::uint32_t n, const BoxOf& box, double grow) : n_(n) {
        if (n_ < 2) return;
        const auto all = [&](std::uint32_t i) {
            const Box3 b = box(i);
            return Box3{b.min - Vec3{grow, grow, grow}, b.max + Vec3{grow, grow, grow}};
        };
        // Where the centres lie, for the curve's grid (min and max: any split gives the same).
        const Box3 centres = tbb::parallel_reduce(
            tbb::blocked_range<std::uint32_t>(0, n_, kGrain), Box3{},
            [&](const auto& r, Box3 acc) {
                for (std::uint32_t i = r.begin(); i != r.end(); ++i) {
                    const Box3 b = all(i);
                    acc.add(0.5 * (b.min + b.max));
                }
                return acc;
            },
            [](Box3 a, const Box3& b) {
                a.add(b);
                return a;
            });
        // Morton codes of the centres on a 2^21 grid over them; ties by index, so the order
        // is one total order whatever the sort.
        std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed;
        detail::resize_huge(keyed, n_);
        const Vec3 lo = centres.min, ext = centres.max - centres.min;
        tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n_, kGrain), [&](const auto& r) {
            for (std::uint32_t i = r.begin(); i != r.end(); ++i) {
                const Box3 b = all(i);
                const Vec3 c = 0.5 * (b.min + b.max);
                std::uint64_t code = 0;
                for (int k = 0; k < 3; ++k) {
                    const double t = ext[k] > 0 ? (c[k] - lo[k]) / ext[k] : 0.0;
                    // NaN and rounding past the ends go to the grid's ends.
                    const double cell = t > 0 ? std::min(t, 1.0) * kGridMax : 0.0;
                    code |= spread_bits(static_cast<std::uint64_t>(cell)) << k;
                }
                keyed[i] = {code, i};
            }
        });
        tbb::parallel_sort(keyed.begin(), keyed.end());
        // The tree in heap order (node k's children 2k + 1, 2k + 2), its leaves (a power of
        // two) from first_leaf_ on: leaf l holds boxes [kLeaf l, kLeaf (l + 1)) of the curve's
        // order; the slots past the last box are empty. Filled from the leaves up, a level at a
        // time.
        const std::uint32_t leaves = (n_ + kLeaf - 1) / kLeaf;
        first_leaf_ = std::bit_ceil(leaves) - 1;
        nodes_.assign(2 * std::size_t{first_leaf_} + 1, FloatBox{});
        detail::resize_huge(order_, n_);
        detail::resize_huge(slots_, leaves);
        tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, leaves, kGrain / kLeaf),
                          [&](const auto& r) {
                              for (std::uint32_t l = r.begin(); l != r.end(); ++l) {
                                  Slots& s = slots_[l];
                                  FloatBox whole;
                                  for (std::uint32_t j = 0; j < kLeaf; ++j) {
                                      const std::uint32_t i = kLeaf * l + j;
                                      FloatBox b;
                                      if (i < n_) {
                                          order_[i] = keyed[i].second;
                                          b = FloatBox::of(all(order_[i]));
                                      }
                                      for (int k = 0; k < 3; ++k) {
                                          s.min[k][j] = b.min[k];
                                          s.max[k][j] = b.max[k];
                                      }
                                      whole.add(b);
                                  }
                                  nodes_[first_leaf_ + l] = whole;
                              }
                          });
        keyed = {};
        for (std::uint32_t first = first_leaf_; first > 0; first = (first - 1) / 2) {
            const std::uint32_t up = (first - 1) / 2;
            tbb::parallel_for(tbb::blocked_range<std::uint32_t>(up, first, kGrain),
                              [&](const auto& r) {
                                  for (std::uint32_t k = r.begin(); k != r.end(); ++k) {
                                      FloatBox b = nodes_[2 * k + 1];
                                      b.add(nodes_[2 * k + 2]);
                                      nodes_[k] = b;
                                  }
                              });
        }
    }

    /// A pair of boxes, by the indices the constructor gave them.
    struct Pair {
        std::uint32_t first, second;
    };

    /// Calls fn(pairs) with every two boxes that meet, each pair once and in some batch of a
    /// few dozen, from all cores at once and in no set order (the batches differ from run to
    /// run; the pairs do not). Once `stop` is true no more batches begin.
    template <class Fn>
    void for_each_pair(Fn&& fn, std::atomic<bool>& stop) const {
        if (n_ < 2) return;
        within(0, 0, fn, stop);
    }

   private:
    // Boxes a leaf holds: the 8 × 8 box tests of two leaves cost less than the node tests
    // and the task they replace.
    static constexpr std::uint32_t kLeaf = 8;
    // The curve's grid: 2^21 cells a side, three coordinates in a 63-bit code.
    static constexpr double kGridMax = static_cast<double>((1u << 21) - 1);
    // Boxes per task of the parallel loops (a few nanoseconds each).
    static constexpr std::uint32_t kGrain = 1u << 14;
    // Nodes this many levels from the root or fewer search their branches as tasks of their
    // own: 4^10 tasks at most, each ample work on a large mesh.
    static constexpr int kParallelDepth = 10;

    // A leaf's boxes, coordinate by coordinate (empty past the last box: they meet nothing).
    struct alignas(16) Slots {
        std::array<std::array<float, kLeaf>, 3> min, max;
    };

    bool is_leaf(std::uint32_t k) const { return k >= first_leaf_; }

    // Which of leaf s's boxes meet the box (x0, y0, z0)-(x1, y1, z1): bit j for box j.
    static std::uint32_t meets_slots(float x0, float y0, float z0, float x1, float y1, float z1,
                                     const Slots& s) {
        std::uint32_t mask = 0;
#if defined(__SSE2__)
        // Four boxes to a test: x86-64 always has SSE2, and GCC does not vectorize the loop below.
        const __m128 vx0 = _mm_set1_ps(x0), vy0 = _mm_set1_ps(y0), vz0 = _mm_set1_ps(z0);
        const __m128 vx1 = _mm_set1_ps(x1), vy1 = _mm_set1_ps(y1), vz1 = _mm_set1_ps(z1);
        for (std::uint32_t h = 0; h < kLeaf; h += 4) {
            __m128 m = _mm_and_ps(_mm_cmple_ps(vx0, _mm_load_ps(&s.max[0][h])),
                                  _mm_cmple_ps(_mm_load_ps(&s.min[0][h]), vx1));
            m = _mm_and_ps(m, _mm_and_ps(_mm_cmple_ps(vy0, _mm_load_ps(&s.max[1][h])),
                                         _mm_cmple_ps(_mm_load_ps(&s.min[1][h]), vy1)));
            m = _mm_and_ps(m, _mm_and_ps(_mm_cmple_ps(vz0, _mm_load_ps(&s.max[2][h])),
                                         _mm_cmple_ps(_mm_load_ps(&s.min[2][h]), vz1)));
            mask |= static_cast<std::uint32_t>(_mm_movemask_ps(m)) << h;
        }
#else
        for (std::uint32_t j = 0; j < kLeaf; ++j) {
            const bool meet = x0 <= s.max[0][j] && s.min[0][j] <= x1 && y0 <= s.max[1][j] &&
                              s.min[1][j] <= y1 && z0 <= s.max[2][j] && s.min[2][j] <= z1;
            mask |= static_cast<std::uint32_t>(meet) << j;
        }
#endif
        return mask;
    }

    // The pairs of leaf nodes a and b that meet (of a leaf with itself, each once): each box
    // of a against all of b's at once (meets_slots()), handed to fn as one batch.
    template <class Fn>
    void leaf_pairs(std::uint32_t a, std::uint32_t b, Fn& fn) const {
        std::array<Pair, kLeaf * kLeaf> batch;  // left uninitialized: written before read
        std::size_t count = 0;
        const std::uint32_t la = a - first_leaf_, lb = b - first_leaf_;
        const Slots& sa = slots_[la];
        const Slots& sb = slots_[lb];
        const std::uint32_t end = std::min(kLeaf, n_ - kLeaf * la);
        for (std::uint32_t i = 0; i < end; ++i) {
            const float x0 = sa.min[0][i], y0 = sa.min[1][i], z0 = sa.min[2][i];
            const float x1 = sa.max[0][i], y1 = sa.max[1][i], z1 = sa.max[2][i];
            std::uint32_t mask = meets_slots(x0, y0, z0, x1, y1, z1, sb);
            if (a == b) mask &= ~((2u << i) - 1);  // within one leaf: j > i only
            for (; mask != 0; mask &= mask - 1) {
                const auto j = static_cast<std::uint32_t>(std::countr_zero(mask));
                batch[count++] = {order_[kLeaf * la + i], order_[kLeaf * lb + j]};
            }
        }
        if (count > 0) fn(std::span<const Pair>(batch.data(), count));
    }

    template <class Fn>
    void within(std::uint32_t k, int depth, Fn& fn, const std::atomic<bool>& stop) const {
        if (stop || nodes_[k].empty()) return;
        if (is_leaf(k)) {
            leaf_pairs(k, k, fn);
            return;
        }
        const std::uint32_t a = 2 * k + 1, b = 2 * k + 2;
        if (depth < kParallelDepth) {
            tbb::parallel_invoke([&] { within(a, depth + 1, fn, stop); },
                                 [&] { within(b, depth + 1, fn, stop); },
                                 [&] { across(a, b, depth + 1, fn, stop); });
            return;
        }
        within(a, depth + 1, fn, stop);
        within(b, depth + 1, fn, stop);
        across(a, b, depth + 1, fn, stop);
    }

    // Nodes x and y are on one level of the tree (a complete one): both leaves or neither.
    template <class Fn>
    void across(std::uint32_t x, std::uint32_t y, int depth, Fn& fn,
                const std::atomic<bool>& stop) const {
        if (stop || !nodes_[x].meets(nodes_[y])) return;
        if (is_leaf(x)) {
            leaf_pairs(x, y, fn);
            return;
        }
        const std::uint32_t x1 = 2 * x + 1, x2 = 2 * x + 2, y1 = 2 * y + 1, y2 = 2 * y + 2;
        if (depth < kParallelDepth) {
            tbb::parallel_invoke([&] { across(x1, y1, depth + 1, fn, stop); },
                                 [&] { across(x1, y2, depth + 1, fn, stop); },
                                 [&] { across(x2, y1, depth + 1, fn, stop); },
                                 [&] { across(x2, y2, depth + 1, fn, stop); });
            return;
        }
        across(x1, y1, depth + 1, fn, stop);
        across(x1, y2, depth + 1, fn, stop);
        across(x2, y1, depth + 1, fn, stop);
        across(x2, y2, depth + 1, fn, stop);
    }

    std::uint32_t n_ = 0;
    std::uint32_t first_leaf_ = 0;
    std::vector<std::uint32_t> order_;  // box indices along the curve
    std::vector<Slots> slots_;          // their boxes, grown, kLeaf to a leaf
    std::vector<FloatBox> nodes_;
};

}  // namespace ncrev::detail
