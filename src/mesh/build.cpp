// Building the half-edge mesh from a facet soup, with healing (../shared/docs/method.md,
// Step 1): exact weld, tolerance weld, degenerate and duplicate facets dropped, edges paired
// (non-manifold edges split by the angular order of their facets), facets oriented per
// component, closed components turned outward (a cavity's shell inward), non-manifold vertices
// split.
//
// Determinism: every parallel loop writes only its own slots over fixed chunks, and every
// choice (which point represents a weld, which facet of a duplicate pair stays, which facets
// pair on a non-manifold edge) is made by input order, never by thread timing.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <unordered_map>

#include "detail/exact_weld.h"
#include "detail/huge_pages.h"
#include "detail/nesting.h"
#include "detail/self_intersection.h"
#include "detail/union_find.h"
#include "ncrev/mesh.h"

namespace ncrev {

namespace {

constexpr std::uint32_t kNone = 0xFFFFFFFFu;

// Default weld tolerance, relative to the bounding-box diagonal. 1e-6 is about eight float32
// ulps at the scale of the model (float32 has 24 bits, ulp ≈ 1.2e-7 × magnitude): it closes the
// cracks left by float rounding of vertices computed twice, and stays orders of magnitude
// below any real edge of a mesh of even 10^8 facets (edges ≈ diagonal / 10^4).
constexpr double kWeldRelativeToDiagonal = 1e-6;
// A model far from the origin has coarser float32 spacing than its size suggests; the
// tolerance never drops below this many ulps of the largest coordinate.
constexpr double kWeldMinUlps = 8;

// Points per chunk in parallel loops: large enough to amortise scheduling, fixed so that the
// work split (and so the result) does not depend on the thread count.
constexpr std::size_t kChunk = 1 << 15;

std::uint64_t bits_of(double v) {
    if (v == 0) v = 0.0;  // -0.0 and 0.0 are the same point
    return std::bit_cast<std::uint64_t>(v);
}

template <class Fn>
void for_chunks(std::size_t n, Fn&& fn) {
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t c = r.begin(); c != r.end(); ++c) {
                              fn(c * kChunk, std::min(n, (c + 1) * kChunk));
                          }
                      });
}

/// Exact weld of float64 points: id[i] = class of point i, classes numbered by first
/// occurrence; pos[k] = the position of class k. Returns the number of classes.
std::uint32_t weld_exact(std::span<const Vec3> pts, std::vector<std::uint32_t>& id,
                         std::vector<Vec3>& pos) {
    const std::size_t n = pts.size();
    detail::resize_huge(id, n);
    detail::ExactWelder<std::uint64_t> welder(n);
    auto key = [](const Vec3& p) {
        return detail::ExactWelder<std::uint64_t>::Key{bits_of(p.x), bits_of(p.y), bits_of(p.z)};
    };
    constexpr std::size_t kPrefetchAhead = 16;  // points: hides the table miss of new vertices
    for (std::size_t i = 0; i < n; ++i) {
        if (i + kPrefetchAhead < n) welder.prefetch(key(pts[i + kPrefetchAhead]));
        id[i] = welder.insert(key(pts[i]));
    }
    detail::resize_huge(pos, welder.size());
    for (std::size_t c = 0; c < welder.size(); ++c) {
        const auto& k = welder.keys()[c];
        pos[c] = {std::bit_cast<double>(k[0]), std::bit_cast<double>(k[1]),
                  std::bit_cast<double>(k[2])};
    }
    return static_cast<std::uint32_t>(welder.size());
}

/// Tolerance weld among `cand` (ascending vertex ids): merges every pair closer than `tol`,
/// transitively. Sets map[v] to the smallest vertex of v's group (identity elsewhere) and
/// returns the number of vertices merged away.
std::uint64_t weld_tolerance(std::span<const Vec3> pos, std::span<const std::uint32_t> cand,
                             double tol, std::vector<std::uint32_t>& map) {
    map.resize(pos.size());
    std::iota(map.begin(), map.end(), 0u);
    const std::size_t n = cand.size();
    if (tol <= 0 || n < 2) return 0;
    // Cells much larger than tol: a point needs a neighbouring cell only when it lies within
    // tol of that cell's side, which is rare, so most points probe a single cell.
    constexpr double kCellOverTol = 16;
    const double cell = kCellOverTol * tol;
    struct Key {
        std::int64_t x, y, z;
        bool operator==(const Key&) const = default;
    };
    auto key_of = [&](const Vec3& p) {
        return Key{static_cast<std::int64_t>(std::floor(p.x / cell)),
                   static_cast<std::int64_t>(std::floor(p.y / cell)),
                   static_cast<std::int64_t>(std::floor(p.z / cell))};
    };
    auto hash_key = [](const Key& k) {
        std::uint64_t h = static_cast<std::uint64_t>(k.x) * 0x9E3779B97F4A7C15ull;
        h ^= std::rotl(static_cast<std::uint64_t>(k.y) * 0xC2B2AE3D27D4EB4Full, 21);
        h ^= std::rotl(static_cast<std::uint64_t>(k.z) * 0x165667B19E3779F9ull, 42);
        h ^= h >> 31;
        return h;
    };
    const std::size_t cap = std::bit_ceil(2 * n + 2);
    std::vector<Key> keys(cap);
    std::vector<std::uint32_t> head(cap, kNone);
    std::vector<std::uint32_t> next(n, kNone);
    auto slot_of = [&](const Key& k, bool create) -> std::size_t {
        std::size_t s = hash_key(k) & (cap - 1);
        while (head[s] != kNone) {
            if (keys[s] == k) return s;
            s = (s + 1) & (cap - 1);
        }
        if (!create) return cap;
        keys[s] = k;
        return s;
    };
    // Insert in reverse so that each cell's list is in ascending order.
    for (std::size_t i = n; i-- > 0;) {
        const std::size_t s = slot_of(key_of(pos[cand[i]]), true);
        next[i] = head[s];
        head[s] = static_cast<std::uint32_t>(i);
    }
    detail::MinUnionFind uf(n);
    const double tol2 = tol * tol;
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 p = pos[cand[i]];
        const Key k = key_of(p);
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            const double base = static_cast<double>((&k.x)[a]) * cell;
            lo[a] = (p[a] - base < tol) ? -1 : 0;
            hi[a] = (base + cell - p[a] < tol) ? 1 : 0;
        }
        for (int dx = lo[0]; dx <= hi[0]; ++dx) {
            for (int dy = lo[1]; dy <= hi[1]; ++dy) {
                for (int dz = lo[2]; dz <= hi[2]; ++dz) {
                    const std::size_t s = slot_of(Key{k.x + dx, k.y + dy, k.z + dz}, false);
                    if (s == cap) continue;
                    for (std::uint32_t j = head[s]; j != kNone; j = next[j]) {
                        if (j >= i) break;  // each pair once; lists are ascending
                        const Vec3 d = pos[cand[j]] - p;
                        if (dot(d, d) <= tol2) uf.unite(static_cast<std::uint32_t>(i), j);
                    }
                }
            }
        }
    }
    std::uint64_t merged = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t r = uf.find(static_cast<std::uint32_t>(i));
        if (r != i) {
            map[cand[i]] = cand[r];
            ++merged;
        }
    }
    return merged;
}

struct PairCounts {
    std::uint64_t nonmanifold_edges = 0;
    std::uint64_t unmatched = 0;
    std::uint64_t duplicates = 0;
};

/// Pairs the half-edges of the facets whose corners are `c` (facet k: c[3k..3k+2]; half-edge
/// h runs c[h] -> c[next(h)]). Two half-edges on one edge become mates (whatever their
/// directions: orientation is fixed later). On an edge with more than two, the facets are
/// ordered by angle around it and each facet running high -> low is paired with the next one
/// running low -> high (counter-clockwise about low -> high): those bound one wedge of
/// material of a consistently oriented solid, so two solids sharing an edge come apart.
/// Facets with the same three vertices as an earlier one are flagged in `dup`.
///
/// Half-edges are bucketed by their lower vertex (a stable counting sort, so each bucket
/// lists its half-edges in index order); buckets are then independent and processed in
/// parallel over fixed vertex ranges.
PairCounts pair_edges(std::span<const std::uint32_t> c, std::span<const Vec3> vpos,
                      std::vector<std::uint32_t>& mate, std::vector<std::uint8_t>& dup) {
    const std::size_t nh = c.size();
    const std::size_t nv = vpos.size();
    auto nxt = [](std::size_t h) { return h % 3 == 2 ? h - 2 : h + 1; };
    auto prv = [](std::size_t h) { return h % 3 == 0 ? h + 2 : h - 1; };
    std::vector<std::uint32_t> start;
    detail::assign_huge(start, nv + 1, 0u);
    for (std::size_t f = 0; f < nh; f += 3) {
        const std::uint32_t a = c[f], b = c[f + 1], d = c[f + 2];
        ++start[std::min(a, b) + 1];
        ++start[std::min(b, d) + 1];
        ++start[std::min(d, a) + 1];
    }
    for (std::size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
    struct Item {
        std::uint32_t other;  // the higher vertex
        std::uint32_t h;
    };
    std::vector<Item> items;
    detail::resize_huge(items, nh);
    {
        std::vector<std::uint32_t> fill;
        detail::reserve_huge(fill, nv);
        fill.assign(start.begin(), start.end() - 1);
        for (std::size_t h = 0; h < nh; ++h) {
            const std::uint32_t a = c[h], b = c[nxt(h)];
            const std::uint32_t lo = std::min(a, b);
            items[fill[lo]++] = {std::max(a, b), static_cast<std::uint32_t>(h)};
        }
    }
    detail::assign_huge(mate, nh, kNone);
    detail::assign_huge(dup, nh / 3, std::uint8_t{0});
    constexpr std::size_t kVertexChunk = 1 << 14;
    const std::size_t chunks = (nv + kVertexChunk - 1) / kVertexChunk;
    std::vector<PairCounts> counts(chunks);
    tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t chunk) {
        PairCounts& pc = counts[chunk];
        struct Around {
            double angle;
            std::uint32_t h;
            bool forward;  // runs low -> high
        };
        std::vector<Around> around;
        auto flag_dup = [&](std::uint32_t h) {
            std::atomic_ref<std::uint8_t>(dup[h / 3]).store(1, std::memory_order_relaxed);
        };
        const std::size_t v_end = std::min(nv, (chunk + 1) * kVertexChunk);
        for (std::size_t v = chunk * kVertexChunk; v < v_end; ++v) {
            Item* bucket = items.data() + start[v];
            const std::size_t size = start[v + 1] - start[v];
            // Insertion sort by (other, h): buckets hold a handful of half-edges.
            for (std::size_t i = 1; i < size; ++i) {
                const Item x = bucket[i];
                std::size_t j = i;
                while (j > 0 && (bucket[j - 1].other > x.other ||
                                 (bucket[j - 1].other == x.other && bucket[j - 1].h > x.h))) {
                    bucket[j] = bucket[j - 1];
                    --j;
                }
                bucket[j] = x;
            }
            for (std::size_t s = 0; s < size;) {
                std::size_t t = s + 1;
                while (t < size && bucket[t].other == bucket[s].other) ++t;
                const std::size_t k = t - s;
                if (k == 1) {
                    ++pc.unmatched;
                } else if (k == 2) {
                    const std::uint32_t x = bucket[s].h, y = bucket[s + 1].h;
                    mate[x] = y;
                    mate[y] = x;
                    // Same edge and same opposite vertex: the same three vertices.
                    if (c[prv(x)] == c[prv(y)]) flag_dup(y);
                } else {
                    ++pc.nonmanifold_edges;
                    for (std::size_t x = s; x < t; ++x) {
                        for (std::size_t y = s; y < x; ++y) {
                            if (c[prv(bucket[x].h)] == c[prv(bucket[y].h)]) flag_dup(bucket[x].h);
                        }
                    }
                    const Vec3 p0 = vpos[v];
                    const Vec3 axis = normalized(vpos[bucket[s].other] - p0);
                    const Vec3 helper = std::abs(axis.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
                    const Vec3 b1 = normalized(cross(axis, helper));
                    const Vec3 b2 = cross(axis, b1);
                    around.clear();
                    for (std::size_t q = s; q < t; ++q) {
                        const std::uint32_t h = bucket[q].h;
                        const Vec3 r = vpos[c[prv(h)]] - p0;
                        around.push_back({std::atan2(dot(r, b2), dot(r, b1)), h, c[h] == v});
                    }
                    std::sort(around.begin(), around.end(), [](const Around& x, const Around& y) {
                        return x.angle != y.angle ? x.angle < y.angle : x.h < y.h;
                    });
                    std::size_t best_offset = 0, best_score = 0;
                    for (std::size_t off = 0; off < 2; ++off) {
                        std::size_t score = 0;
                        for (std::size_t q = 0; q + 1 < k; q += 2) {
                            score += (!around[(off + q) % k].forward &&
                                      around[(off + q + 1) % k].forward);
                        }
                        if (score > best_score) {
                            best_score = score;
                            best_offset = off;
                        }
                    }
                    for (std::size_t q = 0; q + 1 < k; q += 2) {
                        const std::uint32_t x = around[(best_offset + q) % k].h;
                        const std::uint32_t y = around[(best_offset + q + 1) % k].h;
                        mate[x] = y;
                        mate[y] = x;
                    }
                    pc.unmatched += k % 2;
                }
                s = t;
            }
        }
    });
    PairCounts total;
    for (const PairCounts& pc : counts) {
        total.nonmanifold_edges += pc.nonmanifold_edges;
        total.unmatched += pc.unmatched;
    }
    for (std::uint8_t d : dup) total.duplicates += d;
    return total;
}

}  // namespace

double default_weld_tolerance(const Box3& box, std::string* rule) {
    if (box.empty()) {
        if (rule) *rule = "empty model: exact weld only";
        return 0;
    }
    double max_abs = 0;
    for (int a = 0; a < 3; ++a) {
        max_abs = std::max({max_abs, std::abs(box.min[a]), std::abs(box.max[a])});
    }
    const double from_diag = kWeldRelativeToDiagonal * box.diagonal();
    const double ulp = max_abs > 0 ? std::nextafter(static_cast<float>(max_abs),
                                                    std::numeric_limits<float>::infinity()) -
                                         static_cast<float>(max_abs)
                                   : 0.0;
    const double from_ulps = kWeldMinUlps * ulp;
    if (rule) {
        *rule = from_diag >= from_ulps
                    ? "1e-6 x bounding-box diagonal (about 8 float32 ulps at the model's size)"
                    : "8 float32 ulps of the largest coordinate (the model lies far from the "
                      "origin)";
    }
    return std::max(from_diag, from_ulps);
}

/// Friend of Mesh: fills its columns.
class MeshBuilder {
   public:
    /// `owned`: the caller gave its soup away (it is `&soup`): points and triangles are
    /// reused or released as soon as they are no longer needed, to keep the peak low.
    static Result<BuildResult> build(const TriangleSoup& soup, TriangleSoup* owned,
                                     const HealOptions& options, const ProgressFn& progress);
    static Result<BuildResult> fill_holes(BuildResult built, const HealOptions& options,
                                          const ProgressFn& progress);
    static Result<BuildResult> rebuild(
        BuildResult built, const std::map<std::uint32_t, std::vector<std::uint32_t>>& split,
        const std::vector<std::array<std::uint32_t, 3>>& added,
        const std::vector<std::uint32_t>& added_next_to, const HealOptions& options);
};

Result<BuildResult> MeshBuilder::build(const TriangleSoup& soup, TriangleSoup* owned,
                                       const HealOptions& options, const ProgressFn& progress) {
    auto report_progress = [&](std::string_view stage, double f) {
        if (progress) progress(stage, f);
    };
    const std::size_t num_points = soup.points.size();
    const std::size_t num_in = soup.triangles.size();
    if (num_points >= kNone || num_in >= kNone / 3) {
        Error e;
        e.code = ErrorCode::kTooLarge;
        e.message = "mesh too large for 32-bit ids";
        return e;
    }
    for (std::size_t f = 0; f < num_in; ++f) {
        for (std::uint32_t v : soup.triangles[f]) {
            if (v >= num_points) {
                Error e;
                e.code = ErrorCode::kIndexOutOfRange;
                e.message = "facet " + std::to_string(f) + " names point " + std::to_string(v) +
                            " of " + std::to_string(num_points);
                return e;
            }
        }
    }
    const bool attrs = soup.color.size() == num_in && soup.cut.size() == num_in &&
                       soup.surface.size() == num_in && num_in > 0;

    BuildResult out;
    HealReport& rep = out.heal;
    rep.input_facets = num_in;

    // Bounding box of the input points, and the tolerance.
    Box3 box;
    {
        std::vector<Box3> boxes((num_points + kChunk - 1) / kChunk);
        for_chunks(num_points, [&](std::size_t b, std::size_t e) {
            Vec3 lo = soup.points[b], hi = soup.points[b];
            for (std::size_t i = b; i < e; ++i) {
                const Vec3 q = soup.points[i];
                lo = {std::min(lo.x, q.x), std::min(lo.y, q.y), std::min(lo.z, q.z)};
                hi = {std::max(hi.x, q.x), std::max(hi.y, q.y), std::max(hi.z, q.z)};
            }
            boxes[b / kChunk].add(lo);
            boxes[b / kChunk].add(hi);
        });
        for (const Box3& bb : boxes) box.add(bb);
    }
    if (options.weld_tolerance >= 0) {
        rep.tolerance = options.weld_tolerance;
        rep.tolerance_rule = "given by the caller";
    } else {
        rep.tolerance = default_weld_tolerance(box, &rep.tolerance_rule);
    }
    const double tol = rep.tolerance;

    // 1. Exact weld: point -> vertex (unless the reader already welded: then the points are
    // the vertices and the triangles are taken as they are).
    report_progress("weld", 0.0);
    std::vector<std::uint32_t> point_vertex;
    std::vector<Vec3> vpos;
    rep.input_points = num_points + soup.welded_points;
    if (soup.points_distinct) {
        rep.exact_welded_points = soup.welded_points;
        if (owned) {
            vpos = std::move(owned->points);
        } else {
            detail::reserve_huge(vpos, soup.points.size());
            vpos.assign(soup.points.begin(), soup.points.end());
        }
    } else {
        const std::uint32_t num_exact = weld_exact(soup.points, point_vertex, vpos);
        rep.exact_welded_points = num_points - num_exact;
        if (owned) owned->points = {};  // from here on only vpos is read
    }

    // Welded corners; in place of the input triangles when the soup is ours.
    std::vector<std::array<std::uint32_t, 3>> tri;
    if (owned) {
        tri = std::move(owned->triangles);
    } else {
        detail::reserve_huge(tri, num_in);
        tri.assign(soup.triangles.begin(), soup.triangles.end());
    }
    if (!soup.points_distinct) {
        for_chunks(num_in, [&](std::size_t b, std::size_t e) {
            for (std::size_t f = b; f < e; ++f) {
                for (std::uint32_t& v : tri[f]) v = point_vertex[v];
            }
        });
    }
    point_vertex = {};
    report_progress("weld", 1.0);

    // 2. Degenerate facets: a repeated vertex, or a height below the weld tolerance.
    report_progress("pair", 0.0);
    std::vector<std::uint32_t> kept;  // input facet index of each kept facet
    detail::resize_huge(kept, num_in);
    std::iota(kept.begin(), kept.end(), 0u);
    // Facets added by splitting (index >= num_in in `tri`) and the input facet each came from.
    std::vector<std::uint32_t> split_origin;
    const auto source_of = [&](std::uint32_t f) {
        return f < num_in ? f : split_origin[f - num_in];
    };
    // A cap — three distinct vertices in a line, one (c) between the other two (a, b) — that
    // is stitched into the surface (facets beyond each of its three edges) would leave a hole
    // if dropped: the facet beyond its long edge (b, a, d) is split at c into (b, c, d) and
    // (c, a, d), which then meet the cap's other two neighbours, and the cap goes. CAD
    // tessellations make such caps where a face's boundary has a vertex in the middle of the
    // neighbouring face's edge. They also make strips of them, a sliver between a chord and
    // the finer polyline of a curved edge (BRepMesh on NIST FTC 06 at 1e-4 of its size and
    // 0.03 rad: 815k facets, closed, 420 caps). Caps side by side are one sliver, split in
    // when it is stitched in all round, and a cap beyond another's long edge waits until that
    // one has gone, its split facet then beyond it (until the forty-ninth session every cap
    // with a cap beside it was dropped, and that closed mesh had 83 holes).
    const auto split_caps = [&](std::vector<std::uint8_t>& bad) {
        std::vector<std::size_t> caps;
        for (std::size_t k = 0; k < kept.size(); ++k) {
            const auto& t = tri[kept[k]];
            if (bad[k] && t[0] != t[1] && t[1] != t[2] && t[0] != t[2]) caps.push_back(k);
        }
        if (caps.empty()) return;
        const auto key = [](std::uint32_t a, std::uint32_t b) {
            return (std::uint64_t{a} << 32) | b;
        };
        // Directed edge -> kept slot, for the edges between two caps' vertices only: every
        // edge looked up or erased below is one (a cap's three; entries for other edges would
        // be written and never read), and the map of all edges was most of healing on a mesh
        // of a million facets with a few caps (3.7 s, 0.5 s without it). A cap that runs a
        // directed edge another facet runs too (a cap over a cap, a fin hanging off an edge)
        // is not stitched in: `loose`.
        std::vector<std::uint8_t> at_cap(vpos.size(), 0);
        for (std::size_t k : caps) {
            for (const std::uint32_t v : tri[kept[k]]) at_cap[v] = 1;
        }
        std::unordered_map<std::size_t, std::uint32_t> cap_index;
        for (std::size_t i = 0; i < caps.size(); ++i)
            cap_index.emplace(caps[i], static_cast<std::uint32_t>(i));
        std::vector<std::uint8_t> loose(caps.size(), 0);
        std::unordered_map<std::uint64_t, std::size_t> owner;
        const auto own = [&](std::uint32_t u, std::uint32_t v, std::size_t k) {
            if (at_cap[u] && at_cap[v]) owner[key(u, v)] = k;
        };
        for (std::size_t i = 0; i < caps.size(); ++i) {
            const auto& t = tri[kept[caps[i]]];
            for (int j = 0; j < 3; ++j) {
                const auto [it, added] = owner.emplace(key(t[j], t[(j + 1) % 3]), caps[i]);
                if (!added) loose[i] = loose[cap_index.at(it->second)] = 1;
            }
        }
        for (std::size_t k = 0; k < kept.size(); ++k) {
            if (bad[k]) continue;
            const auto& t = tri[kept[k]];
            for (int i = 0; i < 3; ++i) {
                const std::uint32_t u = t[i], v = t[(i + 1) % 3];
                if (!at_cap[u] || !at_cap[v]) continue;
                const auto it = owner.find(key(u, v));
                if (it != owner.end() && bad[it->second]) loose[cap_index.at(it->second)] = 1;
                own(u, v, k);
            }
        }
        // Caps side by side are one sliver, split in only when it is stitched in all round:
        // every edge of its caps has a cap of it or a sound facet beyond, and none is loose.
        // (A fin of two caps hanging off an edge would otherwise split the facet there and open
        // it where the fin goes.)
        detail::MinUnionFind sliver(caps.size());
        for (std::size_t i = 0; i < caps.size(); ++i) {
            const auto& t = tri[kept[caps[i]]];
            for (int j = 0; j < 3; ++j) {
                const auto beyond = owner.find(key(t[(j + 1) % 3], t[j]));
                if (beyond == owner.end()) {
                    loose[i] = 1;
                } else if (bad[beyond->second]) {
                    sliver.unite(static_cast<std::uint32_t>(i), cap_index.at(beyond->second));
                }
            }
        }
        for (std::size_t i = 0; i < caps.size(); ++i)
            if (loose[i]) loose[sliver.find(static_cast<std::uint32_t>(i))] = 1;
        // Caps waiting for the cap beyond their long edge (its slot -> theirs).
        std::unordered_map<std::size_t, std::vector<std::size_t>> waiting;
        std::vector<std::size_t> ready;
        for (std::size_t i = caps.size(); i-- > 0;)
            if (!loose[sliver.find(static_cast<std::uint32_t>(i))]) ready.push_back(caps[i]);
        while (!ready.empty()) {
            const std::size_t k = ready.back();
            ready.pop_back();
            const auto t = tri[kept[k]];
            // The long edge a -> b (its vertex c between them).
            int best = 0;
            double longest = -1;
            for (int i = 0; i < 3; ++i) {
                const Vec3 d = vpos[t[(i + 1) % 3]] - vpos[t[i]];
                if (dot(d, d) > longest) longest = dot(d, d), best = i;
            }
            const std::uint32_t a = t[best], b = t[(best + 1) % 3], c = t[(best + 2) % 3];
            const auto across = owner.find(key(b, a));
            if (across == owner.end() || !owner.count(key(c, b)) || !owner.count(key(a, c))) {
                continue;  // not stitched in: dropping it leaves no hole
            }
            const std::size_t n = across->second;
            if (bad[n]) {  // a cap, to be split first
                waiting[n].push_back(k);
                continue;
            }
            auto& u = tri[kept[n]];
            int at = 0;
            while (u[at] != b) ++at;
            const std::uint32_t d = u[(at + 2) % 3];
            if (u[(at + 1) % 3] != a || d == c) continue;
            u = {b, c, d};
            tri.push_back({c, a, d});
            split_origin.push_back(source_of(kept[n]));
            kept.push_back(static_cast<std::uint32_t>(tri.size() - 1));
            bad.push_back(0);
            const std::size_t nk = kept.size() - 1;
            owner.erase(key(b, a));
            if (const auto own_edge = owner.find(key(a, b));
                own_edge != owner.end() && own_edge->second == k) {
                owner.erase(own_edge);
            }
            own(b, c, n);
            own(c, d, n);
            own(d, b, n);
            own(c, a, nk);
            own(a, d, nk);
            own(d, c, nk);
            ++rep.caps_split;
            // The caps beyond this one's long edge now have the split facet there.
            if (const auto w = waiting.find(k); w != waiting.end()) {
                for (auto cap = w->second.rbegin(); cap != w->second.rend(); ++cap)
                    ready.push_back(*cap);
                waiting.erase(w);
            }
        }
    };
    auto drop_degenerate = [&]() {
        std::vector<std::uint8_t> bad;
        detail::assign_huge(bad, kept.size(), std::uint8_t{0});
        for_chunks(kept.size(), [&](std::size_t b, std::size_t e) {
            for (std::size_t k = b; k < e; ++k) {
                const auto& t = tri[kept[k]];
                if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
                    bad[k] = 1;
                    continue;
                }
                const Vec3 p0 = vpos[t[0]], p1 = vpos[t[1]], p2 = vpos[t[2]];
                const double area2 = norm(cross(p1 - p0, p2 - p0));
                const double longest = std::sqrt(std::max(
                    {dot(p1 - p0, p1 - p0), dot(p2 - p1, p2 - p1), dot(p0 - p2, p0 - p2)}));
                // twice the area / longest edge = the smallest height of the triangle
                if (area2 <= tol * longest) bad[k] = 1;
            }
        });
        split_caps(bad);
        std::size_t w = 0;
        for (std::size_t k = 0; k < kept.size(); ++k) {
            if (bad[k]) {
                ++rep.degenerate_facets_removed;
            } else {
                kept[w++] = kept[k];
            }
        }
        kept.resize(w);
    };
    drop_degenerate();

    // 3. Pair half-edges into edges, dropping duplicate facets (same three vertices as an
    // earlier facet) and, once, welding within the tolerance the vertices of unmatched edges:
    // a crack always leaves unmatched edges at its vertices, while a vertex whose edges all
    // match is sound and is never moved.
    std::vector<std::uint32_t> corner;  // kept facet k: corner[3k .. 3k+2]
    std::vector<std::uint32_t> mate;
    std::vector<std::uint8_t> dup;
    bool tolerance_done = false;
    for (;;) {
        if (corner.empty()) detail::reserve_huge(corner, 3 * kept.size());
        corner.resize(3 * kept.size());
        for_chunks(kept.size(), [&](std::size_t b, std::size_t e) {
            for (std::size_t k = b; k < e; ++k) {
                const auto& t = tri[kept[k]];
                corner[3 * k] = t[0];
                corner[3 * k + 1] = t[1];
                corner[3 * k + 2] = t[2];
            }
        });
        const PairCounts pc = pair_edges(corner, vpos, mate, dup);
        if (pc.duplicates > 0) {
            std::size_t w = 0;
            for (std::size_t k = 0; k < kept.size(); ++k) {
                if (dup[k]) {
                    ++rep.duplicate_facets_removed;
                } else {
                    kept[w++] = kept[k];
                }
            }
            kept.resize(w);
            continue;
        }
        if (!tolerance_done && tol > 0 && pc.unmatched > 0) {
            tolerance_done = true;
            std::vector<std::uint32_t> cand;
            for (std::size_t h = 0; h < corner.size(); ++h) {
                if (mate[h] == kNone) {
                    cand.push_back(corner[h]);
                    cand.push_back(corner[h % 3 == 2 ? h - 2 : h + 1]);
                }
            }
            std::sort(cand.begin(), cand.end());
            cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
            std::vector<std::uint32_t> map;
            rep.welded_vertices = weld_tolerance(vpos, cand, tol, map);
            if (rep.welded_vertices > 0) {
                for (std::uint32_t f : kept) {
                    for (std::uint32_t& v : tri[f]) v = map[v];
                }
                drop_degenerate();
                continue;
            }
        }
        rep.nonmanifold_edges = pc.nonmanifold_edges;
        break;
    }
    dup = {};
    const std::size_t nf = kept.size();
    const std::size_t nh = 3 * nf;

    // 4. Compact the vertices to those the kept facets use (in vertex order).
    {
        std::vector<std::uint32_t> remap;
        detail::assign_huge(remap, vpos.size(), kNone);
        for (std::uint32_t v : corner) remap[v] = 0;
        std::uint32_t nv = 0;
        for (std::size_t v = 0; v < vpos.size(); ++v) {
            if (remap[v] != kNone) {
                vpos[nv] = vpos[v];
                remap[v] = nv++;
            }
        }
        rep.unreferenced_vertices = vpos.size() - nv;
        vpos.resize(nv);
        for_chunks(nh, [&](std::size_t b, std::size_t e) {
            for (std::size_t h = b; h < e; ++h) corner[h] = remap[corner[h]];
        });
    }
    tri = {};
    const std::size_t nv = vpos.size();
    report_progress("pair", 1.0);

    // 6. Orientation: breadth-first over each component in facet order; a neighbour across
    // an edge both facets run the same way must be flipped relative to the current one.
    report_progress("orient", 0.0);
    std::vector<std::uint8_t> flip;
    detail::assign_huge(flip, nf, std::uint8_t{0});
    std::vector<std::uint32_t> comp;
    detail::assign_huge(comp, nf, kNone);
    std::vector<std::uint32_t> comp_start;  // where each component starts in BFS order
    std::vector<std::uint32_t> bfs;
    detail::reserve_huge(bfs, nf);
    for (std::size_t seed = 0; seed < nf; ++seed) {
        if (comp[seed] != kNone) continue;
        const auto c = static_cast<std::uint32_t>(comp_start.size());
        comp_start.push_back(static_cast<std::uint32_t>(bfs.size()));
        comp[seed] = c;
        bfs.push_back(static_cast<std::uint32_t>(seed));
        for (std::size_t q = comp_start.back(); q < bfs.size(); ++q) {
            const std::uint32_t f = bfs[q];
            for (int k = 0; k < 3; ++k) {
                const std::size_t h = 3 * f + k;
                const std::uint32_t m = mate[h];
                if (m == kNone) continue;
                const std::uint32_t g = m / 3;
                const bool same_direction = corner[h] == corner[m];
                const std::uint8_t want = flip[f] ^ (same_direction ? 1 : 0);
                if (comp[g] == kNone) {
                    comp[g] = c;
                    flip[g] = want;
                    bfs.push_back(g);
                } else if (flip[g] != want) {
                    // Non-orientable (a Möbius band): cut this edge.
                    ++rep.orientation_conflicts;
                    mate[h] = kNone;
                    mate[m] = kNone;
                }
            }
        }
    }
    const std::size_t num_comp = comp_start.size();
    bfs = {};
    comp_start = {};
    if (options.orient) {
        // Per-component sums in facet order (sequential memory access; BFS order scatters).
        std::vector<std::uint64_t> size(num_comp, 0), flipped(num_comp, 0);
        for (std::size_t f = 0; f < nf; ++f) {
            ++size[comp[f]];
            flipped[comp[f]] += flip[f];
        }
        // Keep the majority's orientation: flip the minority of each component.
        std::vector<std::uint8_t> invert(num_comp, 0);
        for (std::size_t c = 0; c < num_comp; ++c) {
            if (2 * flipped[c] > size[c]) {
                invert[c] = 1;
                flipped[c] = size[c] - flipped[c];
            }
            rep.flipped_facets += flipped[c];
        }
        // Turn closed components outward: positive signed volume (about the box center, for
        // precision), a cavity's shell inward.
        const Vec3 center = box.empty() ? Vec3{} : 0.5 * (box.min + box.max);
        std::vector<double> volume6(num_comp, 0.0);
        std::vector<std::uint8_t> open(num_comp, 0);
        for (std::size_t f = 0; f < nf; ++f) {
            const std::uint32_t c = comp[f];
            flip[f] ^= invert[c];
            open[c] |= mate[3 * f] == kNone || mate[3 * f + 1] == kNone || mate[3 * f + 2] == kNone;
            const Vec3 p0 = vpos[corner[3 * f]] - center;
            Vec3 p1 = vpos[corner[3 * f + 1]] - center;
            Vec3 p2 = vpos[corner[3 * f + 2]] - center;
            if (flip[f]) std::swap(p1, p2);
            volume6[c] += dot(p0, cross(p1, p2));
        }
        // A closed component inside another an odd number of times is a cavity's shell: it
        // faces into the cavity (negative volume), away from the material around it.
        std::vector<std::uint8_t> closed(num_comp, 0);
        for (std::size_t c = 0; c < num_comp; ++c) closed[c] = !open[c];
        const detail::Nesting nesting = detail::nest_components(
            comp, static_cast<std::uint32_t>(num_comp), closed, tol, [&](std::uint32_t f) {
                return std::array<Vec3, 3>{vpos[corner[3 * std::size_t{f}]],
                                           vpos[corner[3 * std::size_t{f} + 1]],
                                           vpos[corner[3 * std::size_t{f} + 2]]};
            });
        rep.nesting_unchecked = !nesting.complete;
        rep.crossing_unchecked = !nesting.crossing_complete;
        std::vector<std::uint8_t> crosses(num_comp, 0);
        for (const auto& [a, b] : nesting.crossing) crosses[a] = crosses[b] = 1;
        rep.crossing_components =
            static_cast<std::uint64_t>(std::count(crosses.begin(), crosses.end(), 1));
        std::vector<std::uint8_t> turn(num_comp, 0);
        for (std::size_t c = 0; c < num_comp; ++c) {
            if (open[c]) continue;
            const bool cavity = nesting.depth[c] % 2 == 1;
            rep.cavities += cavity;
            if ((volume6[c] < 0) != cavity) {
                turn[c] = 1;
                ++(cavity ? rep.cavities_turned_inward : rep.components_turned_outward);
            }
        }
        for (std::size_t f = 0; f < nf; ++f) flip[f] ^= turn[comp[f]];
    } else {
        std::fill(flip.begin(), flip.end(), 0);
    }
    comp = {};
    report_progress("orient", 1.0);

    // 7. The half-edge columns, in place of the corners and the mates (a face's half-edges
    // stay within it). Flipping facet (v0 v1 v2) to (v0 v2 v1) moves its half-edge in slot i
    // to slot 2 - i.
    report_progress("finish", 0.0);
    Mesh& mesh = out.mesh;
    auto slot = [&](std::uint32_t h) -> std::uint32_t {
        const std::uint32_t f = h / 3, i = h % 3;
        return flip[f] ? 3 * f + (2 - i) : h;
    };
    for_chunks(nf, [&](std::size_t b, std::size_t e) {
        for (std::size_t f = b; f < e; ++f) {
            std::uint32_t* c = &corner[3 * f];
            std::uint32_t* m = &mate[3 * f];
            const std::uint32_t own[3] = {m[0], m[1], m[2]};
            for (int k = 0; k < 3; ++k) {
                const auto h = static_cast<std::uint32_t>(3 * f + k);
                m[slot(h) - 3 * f] = own[k] == kNone ? kNone : slot(own[k]);
            }
            if (flip[f]) std::swap(c[1], c[2]);
        }
    });
    // Both hold nh entries, in room sized for the facets before duplicates and degenerate ones
    // went: a file made largely of those would keep it for the mesh's lifetime.
    for (std::vector<std::uint32_t>* column : {&corner, &mate})
        if (column->capacity() > nh + nh / 8) column->shrink_to_fit();
    mesh.origin_ = std::move(corner);
    mesh.twin_ = std::move(mate);
    flip = {};

    // 8. Split non-manifold vertices: every fan of half-edges around a vertex beyond its
    // first gets a vertex of its own. The outgoing half-edge of a vertex on a boundary is the
    // one without a twin, so that boundary loops can be walked.
    {
        auto& origin = mesh.origin_;
        const auto& twin = mesh.twin_;
        auto nxt = [](std::uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; };
        auto prv = [](std::uint32_t h) { return h % 3 == 0 ? h + 2 : h - 1; };
        std::vector<std::uint8_t> seen, has_fan, counted;
        detail::assign_huge(seen, nh, std::uint8_t{0});
        detail::assign_huge(has_fan, nv, std::uint8_t{0});
        detail::assign_huge(counted, nv, std::uint8_t{0});
        detail::assign_huge(mesh.outgoing_, nv, kNone);
        std::vector<std::uint32_t> fan;
        for (std::uint32_t h = 0; h < nh; ++h) {
            if (seen[h]) continue;
            const std::uint32_t v = origin[h];
            // Rotate one way (twin of prev) until the fan closes or opens; then, if open,
            // the other way (next of twin) from h.
            fan.clear();
            std::uint32_t g = h;
            std::uint32_t boundary_out = kNone;
            bool closed = false;
            for (std::size_t guard = 0; guard <= nh; ++guard) {
                fan.push_back(g);
                seen[g] = 1;
                const std::uint32_t p = prv(g);
                if (twin[p] == kNone) break;
                g = twin[p];
                if (g == h) {
                    closed = true;
                    break;
                }
            }
            if (!closed) {
                g = h;
                for (std::size_t guard = 0; guard <= nh; ++guard) {
                    if (twin[g] == kNone) {
                        boundary_out = g;
                        break;
                    }
                    g = nxt(twin[g]);
                    fan.push_back(g);
                    seen[g] = 1;
                }
            }
            std::uint32_t target = v;
            if (has_fan[v]) {
                if (!counted[v]) {
                    counted[v] = 1;
                    ++rep.nonmanifold_vertices;
                }
                target = static_cast<std::uint32_t>(vpos.size());
                vpos.push_back(vpos[v]);
                mesh.outgoing_.push_back(kNone);
                for (std::uint32_t x : fan) origin[x] = target;
            }
            has_fan[v] = 1;
            mesh.outgoing_[target] = closed ? h : boundary_out;
        }
    }
    mesh.position_ = std::move(vpos);

    // 9. Per-face columns carried from the input.
    for (std::uint32_t& f : kept) f = source_of(f);
    mesh.source_face_ = std::move(kept);
    if (attrs) {
        detail::resize_huge(mesh.color_, nf);
        detail::resize_huge(mesh.cut_, nf);
        detail::resize_huge(mesh.surface_, nf);
        for (std::size_t f = 0; f < nf; ++f) {
            const std::uint32_t s = mesh.source_face_[f];
            mesh.color_[f] = soup.color[s];
            mesh.cut_[f] = soup.cut[s];
            mesh.surface_[f] = soup.surface[s];
        }
    }
    report_progress("finish", 1.0);
    return out;
}

namespace {

// Hole filling. A file that lost a few facets has small boundary loops in an otherwise closed
// part; a deliberate opening, a sheet's border, a loose facet's own edges are large beside
// their component. A loop is filled when it is one missing facet (three edges), or has at most
// kMaxHoleEdges edges and a perimeter at most kMaxHolePerimeter times its component's box
// diagonal: a sheet's, a loose facet's or an open box's border is at least twice its diagonal
// (a quarter of that is the bound); a missing facet's is a few facets' edges, a missing end of
// a bar a small part of its length. And only when every loop of the component is, and the
// component then bounds a volume (a sheet or a loose facet would close into a pillow of none).
// The edge bound also keeps the ear clipping (quadratic in the edges) cheap. Before that, cracks
// along T-junctions (a vertex of one face's tessellation in the middle of the neighbouring
// face's edge) are closed whatever their length, by splitting the facets at the vertices on
// their open edges (t_junctions()): that adds no surface.
constexpr std::size_t kMaxHoleEdges = 64;
constexpr double kMaxHolePerimeter = 0.5;

/// Facets closing the loop `loop` (vertex ids in the order of its boundary half-edges), each
/// running the loop's edges the other way, as a neighbour facet would: ear clipping in the
/// plane of the loop's Newell normal. Empty when no ear is found (a loop that folds over
/// itself in that plane) or the loop has no area.
std::vector<std::array<std::uint32_t, 3>> close_loop(const Mesh& m,
                                                     const std::vector<std::uint32_t>& loop) {
    std::vector<std::array<std::uint32_t, 3>> out;
    const std::size_t k = loop.size();
    Vec3 n{}, c{};
    for (std::size_t i = 0; i < k; ++i) c += m.position(VertexId(loop[i]));
    c = c / static_cast<double>(k);
    for (std::size_t i = 0; i < k; ++i) {
        n += cross(m.position(VertexId(loop[i])) - c, m.position(VertexId(loop[(i + 1) % k])) - c);
    }
    if (norm(n) == 0) return out;
    n = normalized(n);
    const Vec3 u = normalized(cross(std::abs(n.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0}, n));
    const Vec3 v = cross(n, u);
    struct P2 {
        double x, y;
    };
    std::vector<P2> p(k);
    for (std::size_t i = 0; i < k; ++i) {
        const Vec3 q = m.position(VertexId(loop[i])) - c;
        p[i] = {dot(q, u), dot(q, v)};
    }
    // The loop runs counter-clockwise about its Newell normal.
    const auto turn = [&](std::size_t a, std::size_t b, std::size_t d) {
        return (p[b].x - p[a].x) * (p[d].y - p[a].y) - (p[b].y - p[a].y) * (p[d].x - p[a].x);
    };
    std::vector<std::size_t> ring(k);
    for (std::size_t i = 0; i < k; ++i) ring[i] = i;
    while (ring.size() > 3) {
        bool clipped = false;
        for (std::size_t i = 0; i < ring.size() && !clipped; ++i) {
            const std::size_t a = ring[(i + ring.size() - 1) % ring.size()], b = ring[i],
                              d = ring[(i + 1) % ring.size()];
            if (turn(a, b, d) <= 0) continue;
            bool empty = true;
            for (const std::size_t j : ring) {
                if (j == a || j == b || j == d) continue;
                if (turn(a, b, j) >= 0 && turn(b, d, j) >= 0 && turn(d, a, j) >= 0) {
                    empty = false;
                    break;
                }
            }
            if (!empty) continue;
            out.push_back({loop[a], loop[d], loop[b]});
            ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(i));
            clipped = true;
        }
        if (!clipped) return {};
    }
    out.push_back({loop[ring[0]], loop[ring[2]], loop[ring[1]]});
    return out;
}

/// Boundary vertices strictly inside boundary edges, within `tol` of them (T-junctions: a
/// vertex of one face's tessellation in the middle of the neighbouring face's edge), as the
/// face to split and its vertices along that edge, in order: {half-edge, v1, v2 ...}. Each
/// edge looks only at the vertices in its slab along the axis it spans least (sorted
/// coordinates), so a mesh's boundary costs about its size. Faces with more than one such edge
/// are left as they are (a fan would not do).
std::map<std::uint32_t, std::vector<std::uint32_t>> t_junctions(const Mesh& m, double tol) {
    std::map<std::uint32_t, std::vector<std::uint32_t>> out;
    const std::size_t nh = m.num_halfedges();
    std::vector<std::uint32_t> edges, vertices;
    for (std::size_t h = 0; h < nh; ++h) {
        if (m.twins()[h] != HalfedgeId::kInvalid) continue;
        edges.push_back(static_cast<std::uint32_t>(h));
        vertices.push_back(m.origins()[h]);
    }
    std::sort(vertices.begin(), vertices.end());
    vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
    std::array<std::vector<std::pair<double, std::uint32_t>>, 3> by;  // per axis, sorted
    for (int axis = 0; axis < 3; ++axis) {
        for (const std::uint32_t v : vertices)
            by[axis].emplace_back(m.position(VertexId(v))[axis], v);
        std::sort(by[axis].begin(), by[axis].end());
    }
    std::vector<std::uint32_t> twice;  // faces with a second such edge
    for (const std::uint32_t h : edges) {
        const Vec3 p = m.position(m.origin(HalfedgeId(h))), q = m.position(m.target(HalfedgeId(h)));
        const double len = norm(q - p);
        if (len <= 2 * tol) continue;
        int axis = 0;
        for (int k = 1; k < 3; ++k) {
            if (std::abs(q[k] - p[k]) < std::abs(q[axis] - p[axis])) axis = k;
        }
        const double lo = std::min(p[axis], q[axis]) - tol, hi = std::max(p[axis], q[axis]) + tol;
        auto it =
            std::lower_bound(by[axis].begin(), by[axis].end(), std::pair{lo, std::uint32_t{0}});
        std::vector<std::pair<double, std::uint32_t>> inside;
        for (; it != by[axis].end() && it->first <= hi; ++it) {
            const Vec3 x = m.position(VertexId(it->second));
            const double t = dot(x - p, q - p) / (len * len);
            if (t * len <= tol || (1 - t) * len <= tol) continue;
            if (norm(x - (p + t * (q - p))) > tol) continue;
            inside.emplace_back(t, it->second);
        }
        if (inside.empty()) continue;
        std::sort(inside.begin(), inside.end());
        const std::uint32_t f = h / 3;
        if (out.count(f)) {
            twice.push_back(f);
            continue;
        }
        std::vector<std::uint32_t> split{h};
        for (const auto& [t, v] : inside) split.push_back(v);
        out.emplace(f, std::move(split));
    }
    for (const std::uint32_t f : twice) out.erase(f);
    return out;
}

}  // namespace

/// `built`'s faces again, those in `split` split along one edge at the vertices on it, then the
/// facets `added` (each beside face `added_next_to[k]`), built with the same options (holes
/// and cracks aside): the faces keep their input facets, the added ones have none. The report
/// is the first build's, with what the second found among the new facets (degenerate ones,
/// caps, duplicates); its other counts (non-manifold edges and vertices, flips, conflicts)
/// find the first build's defects again, in its vertices that the exact weld joins again. What
/// depends on which components are closed is the second's: a part closed by its filled hole
/// first gets its cavities and crossings (the first build saw it open, so neither), and the
/// components it turns are added to the first's. (A cavity's shell given facing in, in a part
/// with a hole, is turned out by the first build and back in by the second: counted both ways.)
Result<BuildResult> MeshBuilder::rebuild(
    BuildResult built, const std::map<std::uint32_t, std::vector<std::uint32_t>>& split,
    const std::vector<std::array<std::uint32_t, 3>>& added,
    const std::vector<std::uint32_t>& added_next_to, const HealOptions& options) {
    const Mesh& m = built.mesh;
    const std::uint32_t nf = static_cast<std::uint32_t>(m.num_faces());
    TriangleSoup soup;
    soup.points.assign(m.positions().begin(), m.positions().end());
    std::vector<std::uint32_t> from;  // per facet of `soup`, the face it comes from
    for (std::uint32_t f = 0; f < nf; ++f) {
        const auto it = split.find(f);
        if (it == split.end()) {
            soup.triangles.push_back({m.vertex(FaceId(f), 0).idx(), m.vertex(FaceId(f), 1).idx(),
                                      m.vertex(FaceId(f), 2).idx()});
            from.push_back(f);
            continue;
        }
        // (p, q, r) with p -> q the split edge: (p, s1, r), (s1, s2, r) ... (sk, q, r).
        const HalfedgeId h(it->second.front());
        const std::uint32_t q = m.target(h).idx(), r = m.origin(Mesh::prev(h)).idx();
        std::uint32_t p = m.origin(h).idx();
        for (std::size_t i = 1; i <= it->second.size(); ++i) {
            const std::uint32_t s = i < it->second.size() ? it->second[i] : q;
            soup.triangles.push_back({p, s, r});
            from.push_back(f);
            p = s;
        }
    }
    const std::size_t own = soup.triangles.size();
    soup.triangles.insert(soup.triangles.end(), added.begin(), added.end());
    from.insert(from.end(), added_next_to.begin(), added_next_to.end());
    if (m.has_attributes()) {
        for (std::size_t k = 0; k < soup.triangles.size(); ++k) {
            soup.color.push_back(m.colors()[from[k]]);  // an added facet: the tool beside it
            soup.cut.push_back(k < own ? m.cuts()[from[k]] : -1);
            soup.surface.push_back(k < own ? m.surfaces()[from[k]] : -1);  // added: none known
        }
    }
    HealOptions again = options;
    again.fill_holes = false;
    again.weld_tolerance = built.heal.tolerance;
    Result<BuildResult> rebuilt = build(soup, &soup, again, {});
    if (!rebuilt.ok()) return rebuilt;
    for (std::uint32_t& s : rebuilt->mesh.source_face_) {
        s = s < own ? m.source_face_[from[s]] : std::numeric_limits<std::uint32_t>::max();
    }
    HealReport& heal = built.heal;
    const HealReport& second = rebuilt->heal;
    heal.degenerate_facets_removed += second.degenerate_facets_removed;
    heal.caps_split += second.caps_split;
    heal.duplicate_facets_removed += second.duplicate_facets_removed;
    heal.components_turned_outward += second.components_turned_outward;
    heal.cavities_turned_inward += second.cavities_turned_inward;
    heal.cavities = second.cavities;
    heal.nesting_unchecked = second.nesting_unchecked;
    heal.crossing_components = second.crossing_components;
    heal.crossing_unchecked = second.crossing_unchecked;
    rebuilt->heal = std::move(heal);
    return rebuilt;
}

/// Closes the cracks along T-junctions of `built` (faces split at the vertices across), then
/// its small holes (kMaxHoleEdges, kMaxHolePerimeter) with new facets.
Result<BuildResult> MeshBuilder::fill_holes(BuildResult built, const HealOptions& options,
                                            const ProgressFn& progress) {
    const auto open = [](const Mesh& m) {
        for (const std::uint32_t t : m.twins()) {
            if (t == HalfedgeId::kInvalid) return true;
        }
        return false;
    };
    if (!open(built.mesh)) return built;
    if (progress) progress("fill holes", 0.0);
    if (auto split = t_junctions(built.mesh, built.heal.tolerance); !split.empty()) {
        const std::size_t cracked = split.size();
        Result<BuildResult> r = rebuild(std::move(built), split, {}, {}, options);
        if (!r.ok()) return r;
        built = std::move(r).value();
        built.heal.facets_split_at_t_junctions = cracked;
        if (!open(built.mesh)) {
            if (progress) progress("fill holes", 1.0);
            return built;
        }
    }
    const Mesh& m = built.mesh;
    const std::size_t nf = m.num_faces();
    std::vector<std::array<std::uint32_t, 3>> added;
    std::vector<std::uint32_t> added_next_to;  // a face beside each added facet's loop
    const Components components = face_components(m);
    const std::vector<std::uint32_t>& comp = components.of_face;
    std::vector<Box3> box(components.count());
    for (std::size_t f = 0; f < nf; ++f) {
        for (int i = 0; i < 3; ++i)
            box[comp[f]].add(m.position(m.vertex(FaceId(static_cast<std::uint32_t>(f)), i)));
    }
    // Per component: its loops that would be filled, and whether all of them would.
    struct Fill {
        std::vector<std::array<std::uint32_t, 3>> facets;
        std::uint32_t next_to = 0;
    };
    std::vector<std::vector<Fill>> fills(box.size());
    std::vector<std::uint8_t> all_filled(box.size(), 1);
    std::vector<std::uint32_t> loop;
    for (const std::vector<HalfedgeId>& edges : boundary_loops(m)) {
        loop.clear();
        double perimeter = 0;
        for (const HalfedgeId g : edges) {
            loop.push_back(m.origin(g).idx());
            perimeter += norm(m.position(m.target(g)) - m.position(m.origin(g)));
        }
        const std::uint32_t face = edges.front().idx() / 3, c = comp[face];
        // One missing facet (three edges), or a hole small beside its part.
        const bool small = loop.size() == 3 || (loop.size() <= kMaxHoleEdges &&
                                                perimeter <= kMaxHolePerimeter * box[c].diagonal());
        auto facets = loop.size() >= 3 && small ? close_loop(m, loop)
                                                : std::vector<std::array<std::uint32_t, 3>>{};
        if (facets.empty()) {
            all_filled[c] = 0;
            continue;
        }
        fills[c].push_back({std::move(facets), face});
    }
    // A component is filled only when that closes it into a solid: a volume beyond a sheet's of
    // the weld tolerance's thickness (a loose facet, a flat patch would close into a pillow of
    // no volume).
    std::vector<double> volume6(box.size(), 0.0), area(box.size(), 0.0);
    const auto add_facet = [&](std::uint32_t c, Vec3 a, Vec3 b, Vec3 d) {
        const Vec3 o = 0.5 * (box[c].min + box[c].max);
        volume6[c] += dot(a - o, cross(b - o, d - o));
        area[c] += 0.5 * norm(cross(b - a, d - a));
    };
    for (std::uint32_t f = 0; f < nf; ++f) {
        const std::uint32_t c = comp[f];
        if (!all_filled[c] || fills[c].empty()) continue;
        add_facet(c, m.position(m.vertex(FaceId(f), 0)), m.position(m.vertex(FaceId(f), 1)),
                  m.position(m.vertex(FaceId(f), 2)));
    }
    for (std::size_t c = 0; c < box.size(); ++c) {
        if (!all_filled[c] || fills[c].empty()) continue;
        for (const Fill& fill : fills[c]) {
            for (const auto& t : fill.facets) {
                add_facet(static_cast<std::uint32_t>(c), m.position(VertexId(t[0])),
                          m.position(VertexId(t[1])), m.position(VertexId(t[2])));
            }
        }
        if (std::abs(volume6[c]) / 6 <= area[c] * built.heal.tolerance) continue;
        for (const Fill& fill : fills[c]) {
            ++built.heal.holes_filled;
            for (const auto& t : fill.facets) {
                added.push_back(t);
                added_next_to.push_back(fill.next_to);
            }
        }
    }
    if (!added.empty()) {
        const std::size_t count = added.size();
        Result<BuildResult> r = rebuild(std::move(built), {}, added, added_next_to, options);
        if (!r.ok()) return r;
        built = std::move(r).value();
        built.heal.hole_facets_added = count;
    }
    if (progress) progress("fill holes", 1.0);
    return built;
}

namespace {

/// Healing's last step, on the mesh as built (holes filled, once): the facet pairs of one
/// component that cross each other, reported, not mended. Its facets are turned as the
/// orientation made them, so that two across an edge agree on their sides (a crossing through
/// the border between them is told by the wedge they make); where nothing was oriented, no
/// border crossing is told.
void report_self_intersections(BuildResult& built, const HealOptions& options,
                               const ProgressFn& progress) {
    if (progress) progress("self-intersections", 0.0);
    const SelfIntersectionReport crossed =
        find_self_intersections(built.mesh, built.heal.tolerance, options.orient);
    built.heal.self_intersections = crossed.pairs;
    built.heal.self_intersection_at = crossed.at;
    built.heal.self_intersection_unchecked = !crossed.complete;
    if (progress) progress("self-intersections", 1.0);
}

Result<BuildResult> heal_rest(Result<BuildResult> built, const HealOptions& options,
                              const ProgressFn& progress) {
    if (!built.ok()) return built;
    if (options.fill_holes) {
        built = MeshBuilder::fill_holes(std::move(built).value(), options, progress);
        if (!built.ok()) return built;
    }
    report_self_intersections(*built, options, progress);
    return built;
}

}  // namespace

SelfIntersectionReport find_self_intersections(const Mesh& m, double tolerance, bool oriented) {
    const auto ids = [&](std::uint32_t f) {
        return std::array<std::uint32_t, 3>{m.vertex(FaceId(f), 0).idx(),
                                            m.vertex(FaceId(f), 1).idx(),
                                            m.vertex(FaceId(f), 2).idx()};
    };
    const auto corners = [&](std::uint32_t f) {
        return std::array<Vec3, 3>{m.position(m.vertex(FaceId(f), 0)),
                                   m.position(m.vertex(FaceId(f), 1)),
                                   m.position(m.vertex(FaceId(f), 2))};
    };
    const auto across = [&](std::uint32_t f, int k, std::uint32_t& g, std::array<Vec3, 3>& other,
                            std::array<std::uint32_t, 3>& vids) {
        const HalfedgeId h = Mesh::halfedge(FaceId(f), k);
        if (!oriented || m.is_boundary(h)) return false;
        g = Mesh::face(m.twin(h)).idx();
        other = corners(g);
        vids = ids(g);
        return true;
    };
    return detail::self_intersections(face_components(m).of_face, tolerance, corners, ids, across);
}

Result<BuildResult> build_mesh(const TriangleSoup& soup, const HealOptions& options,
                               const ProgressFn& progress) {
    return heal_rest(MeshBuilder::build(soup, nullptr, options, progress), options, progress);
}

Result<BuildResult> build_mesh(TriangleSoup&& soup, const HealOptions& options,
                               const ProgressFn& progress) {
    TriangleSoup owned = std::move(soup);
    return heal_rest(MeshBuilder::build(owned, &owned, options, progress), options, progress);
}

}  // namespace ncrev
