// Building the half-edge mesh from a facet soup, with healing (../shared/docs/method.md,
// Step 1): exact weld, tolerance weld, degenerate and duplicate facets dropped, edges paired
// (non-manifold edges split by the angular order of their facets), facets oriented per
// component, closed components turned outward, non-manifold vertices split.
//
// Determinism: every parallel loop writes only its own slots over fixed chunks, and every
// choice (which point represents a weld, which facet of a duplicate pair stays, which facets
// pair on a non-manifold edge) is made by input order, never by thread timing.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <numeric>

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
// Hash partitions of the exact weld: a power of two well above the core count, so partitions
// balance, and small enough that each partition's table stays in cache-friendly sizes.
constexpr int kPartitionBits = 6;
constexpr std::size_t kPartitions = std::size_t{1} << kPartitionBits;

std::uint64_t bits_of(double v) {
    if (v == 0) v = 0.0;  // -0.0 and 0.0 are the same point
    return std::bit_cast<std::uint64_t>(v);
}

std::uint64_t hash_point(const Vec3& p) {
    std::uint64_t h = bits_of(p.x) * 0x9E3779B97F4A7C15ull;
    h ^= std::rotl(bits_of(p.y) * 0xC2B2AE3D27D4EB4Full, 21);
    h ^= std::rotl(bits_of(p.z) * 0x165667B19E3779F9ull, 42);
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 32;
    return h;
}

bool same_point(const Vec3& a, const Vec3& b) {
    return bits_of(a.x) == bits_of(b.x) && bits_of(a.y) == bits_of(b.y) &&
           bits_of(a.z) == bits_of(b.z);
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

/// Exact weld: id[i] = index of point i's class, classes numbered by first occurrence.
/// Returns the number of classes; rep[k] = first point of class k.
std::uint32_t weld_exact(std::span<const Vec3> pts, std::vector<std::uint32_t>& id,
                         std::vector<std::uint32_t>& rep) {
    const std::size_t n = pts.size();
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    // 1. Stable counting sort of point indices by hash partition.
    std::vector<std::uint32_t> counts(chunks * kPartitions, 0);
    for_chunks(n, [&](std::size_t b, std::size_t e) {
        std::uint32_t* c = &counts[(b / kChunk) * kPartitions];
        for (std::size_t i = b; i < e; ++i) ++c[hash_point(pts[i]) >> (64 - kPartitionBits)];
    });
    std::vector<std::size_t> part_begin(kPartitions + 1, 0);
    std::vector<std::size_t> offset(chunks * kPartitions);
    std::size_t total = 0;
    for (std::size_t p = 0; p < kPartitions; ++p) {
        part_begin[p] = total;
        for (std::size_t c = 0; c < chunks; ++c) {
            offset[c * kPartitions + p] = total;
            total += counts[c * kPartitions + p];
        }
    }
    part_begin[kPartitions] = total;
    counts = {};
    std::vector<std::uint32_t> order(n);
    for_chunks(n, [&](std::size_t b, std::size_t e) {
        std::size_t* o = &offset[(b / kChunk) * kPartitions];
        for (std::size_t i = b; i < e; ++i) {
            order[o[hash_point(pts[i]) >> (64 - kPartitionBits)]++] = static_cast<std::uint32_t>(i);
        }
    });
    offset = {};
    // 2. Each partition: an open-addressing table; rep = first index with the same bits.
    id.assign(n, 0);
    tbb::parallel_for(std::size_t{0}, kPartitions, [&](std::size_t p) {
        const std::size_t b = part_begin[p], e = part_begin[p + 1];
        if (b == e) return;
        // Slots hold (hash low 32 bits, point index + 1); sized for at most half load, grown
        // as classes appear, so memory follows the number of distinct points.
        std::size_t cap = std::bit_ceil(std::max<std::size_t>(64, (e - b) / 2));
        std::vector<std::uint64_t> table(cap, 0);
        std::size_t used = 0;
        auto insert_slot = [&](std::vector<std::uint64_t>& t, std::uint64_t entry) {
            const std::size_t mask = t.size() - 1;
            std::size_t s = static_cast<std::uint32_t>(entry >> 32) & mask;
            while (t[s] != 0) s = (s + 1) & mask;
            t[s] = entry;
        };
        for (std::size_t k = b; k < e; ++k) {
            const std::uint32_t i = order[k];
            const auto h32 = static_cast<std::uint32_t>(hash_point(pts[i]));
            const std::size_t mask = cap - 1;
            std::size_t s = h32 & mask;
            std::uint32_t found = kNone;
            while (table[s] != 0) {
                const std::uint64_t entry = table[s];
                if (static_cast<std::uint32_t>(entry >> 32) == h32) {
                    const auto j = static_cast<std::uint32_t>(entry) - 1;
                    if (same_point(pts[j], pts[i])) {
                        found = j;
                        break;
                    }
                }
                s = (s + 1) & mask;
            }
            if (found != kNone) {
                id[i] = found;
                continue;
            }
            id[i] = i;
            table[s] = (std::uint64_t{h32} << 32) | (i + 1);
            if (2 * ++used > cap) {
                std::vector<std::uint64_t> bigger(2 * cap, 0);
                for (std::uint64_t entry : table) {
                    if (entry != 0) insert_slot(bigger, entry);
                }
                table.swap(bigger);
                cap *= 2;
            }
        }
    });
    // 3. Number the classes by first occurrence (id[i] <= i, so one forward pass suffices).
    std::uint32_t next = 0;
    rep.clear();
    for (std::size_t i = 0; i < n; ++i) {
        if (id[i] == i) {
            rep.push_back(static_cast<std::uint32_t>(i));
            id[i] = next++;
        } else {
            id[i] = id[id[i]];
        }
    }
    return next;
}

/// Union-find whose root is always the smallest index of its set: the result does not depend
/// on the order of the unions.
struct MinUnionFind {
    std::vector<std::uint32_t> parent;
    explicit MinUnionFind(std::size_t n) : parent(n) {
        std::iota(parent.begin(), parent.end(), 0u);
    }
    std::uint32_t find(std::uint32_t a) {
        while (parent[a] != a) {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        return a;
    }
    void unite(std::uint32_t a, std::uint32_t b) {
        a = find(a);
        b = find(b);
        if (a == b) return;
        if (a < b) std::swap(a, b);
        parent[a] = b;
    }
};

/// Tolerance weld of distinct points: merges every pair closer than `tol` (transitively).
/// Returns map[u] = the merged class's id (numbered by first occurrence), and the count.
std::uint32_t weld_tolerance(std::span<const Vec3> pos, double tol, std::vector<std::uint32_t>& map) {
    const std::size_t n = pos.size();
    map.resize(n);
    if (tol <= 0 || n == 0) {
        std::iota(map.begin(), map.end(), 0u);
        return static_cast<std::uint32_t>(n);
    }
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
    // Insert in reverse so that each cell's list is in ascending index order.
    for (std::size_t i = n; i-- > 0;) {
        const std::size_t s = slot_of(key_of(pos[i]), true);
        next[i] = head[s];
        head[s] = static_cast<std::uint32_t>(i);
    }
    MinUnionFind uf(n);
    const double tol2 = tol * tol;
    for (std::size_t i = 0; i < n; ++i) {
        const Vec3 p = pos[i];
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
                        const Vec3 d = pos[j] - p;
                        if (dot(d, d) <= tol2) uf.unite(static_cast<std::uint32_t>(i), j);
                    }
                }
            }
        }
    }
    std::uint32_t count = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t r = uf.find(static_cast<std::uint32_t>(i));
        map[i] = (r == i) ? count++ : map[r];
    }
    return count;
}

/// Stable bucket sort of `n` items by key in [0, num_keys): returns offsets (num_keys + 1)
/// and fills `items` with item indices grouped by key, ascending within a key.
void bucket_by_key(std::size_t n, std::size_t num_keys,
                   const std::function<std::uint32_t(std::size_t)>& key,
                   std::vector<std::uint32_t>& offsets, std::vector<std::uint32_t>& items) {
    offsets.assign(num_keys + 1, 0);
    for (std::size_t i = 0; i < n; ++i) ++offsets[key(i) + 1];
    for (std::size_t k = 0; k < num_keys; ++k) offsets[k + 1] += offsets[k];
    items.resize(n);
    std::vector<std::uint32_t> fill(offsets.begin(), offsets.end() - 1);
    for (std::size_t i = 0; i < n; ++i) items[fill[key(i)]++] = static_cast<std::uint32_t>(i);
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
    static Result<BuildResult> build(const TriangleSoup& soup, const HealOptions& options,
                                     const ProgressFn& progress);
};

Result<BuildResult> MeshBuilder::build(const TriangleSoup& soup, const HealOptions& options,
                                       const ProgressFn& progress) {
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
    rep.input_points = num_points;

    // Bounding box of the points the facets use, and the tolerance.
    Box3 box;
    {
        std::vector<Box3> boxes((num_in + kChunk - 1) / kChunk);
        for_chunks(num_in, [&](std::size_t b, std::size_t e) {
            Box3& bb = boxes[b / kChunk];
            for (std::size_t f = b; f < e; ++f) {
                for (std::uint32_t v : soup.triangles[f]) bb.add(soup.points[v]);
            }
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

    // 1. Welds: point -> vertex.
    report_progress("weld", 0.0);
    std::vector<std::uint32_t> point_vertex;
    std::vector<std::uint32_t> class_rep;
    const std::uint32_t num_exact = weld_exact(soup.points, point_vertex, class_rep);
    rep.exact_welded_points = num_points - num_exact;
    std::vector<Vec3> vpos(num_exact);
    for (std::uint32_t k = 0; k < num_exact; ++k) vpos[k] = soup.points[class_rep[k]];
    class_rep = {};
    std::vector<std::uint32_t> merge;
    const std::uint32_t num_merged = weld_tolerance(vpos, tol, merge);
    rep.welded_vertices = num_exact - num_merged;
    if (num_merged != num_exact) {
        // The class keeps the position of its first point (its smallest index).
        std::vector<Vec3> merged(num_merged);
        for (std::size_t u = num_exact; u-- > 0;) merged[merge[u]] = vpos[u];
        vpos.swap(merged);
        for_chunks(num_points, [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i) point_vertex[i] = merge[point_vertex[i]];
        });
    }
    merge = {};
    report_progress("weld", 1.0);

    // 2. Degenerate facets: a repeated vertex, or a height below the weld tolerance.
    report_progress("clean", 0.0);
    std::vector<std::array<std::uint32_t, 3>> tri(num_in);
    std::vector<std::uint8_t> degenerate(num_in, 0);
    for_chunks(num_in, [&](std::size_t b, std::size_t e) {
        for (std::size_t f = b; f < e; ++f) {
            const auto& t = soup.triangles[f];
            const std::array<std::uint32_t, 3> c = {point_vertex[t[0]], point_vertex[t[1]],
                                                    point_vertex[t[2]]};
            tri[f] = c;
            if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) {
                degenerate[f] = 1;
                continue;
            }
            const Vec3 a = vpos[c[0]], bb = vpos[c[1]], cc = vpos[c[2]];
            const double area2 = norm(cross(bb - a, cc - a));
            const double longest =
                std::sqrt(std::max({dot(bb - a, bb - a), dot(cc - bb, cc - bb), dot(a - cc, a - cc)}));
            // twice the area / longest edge = the smallest height of the triangle
            if (area2 <= tol * longest) degenerate[f] = 2;
        }
    });
    point_vertex = {};
    std::vector<std::uint32_t> kept;  // input facet index of each kept facet
    kept.reserve(num_in);
    for (std::size_t f = 0; f < num_in; ++f) {
        if (degenerate[f]) {
            ++rep.degenerate_facets_removed;
        } else {
            kept.push_back(static_cast<std::uint32_t>(f));
        }
    }
    degenerate = {};

    // 3. Duplicate facets: same three vertices (in any order) as an earlier facet.
    {
        std::vector<std::uint32_t> offsets, items;
        auto min_vertex = [&](std::size_t k) {
            const auto& t = tri[kept[k]];
            return std::min({t[0], t[1], t[2]});
        };
        bucket_by_key(kept.size(), vpos.size(), min_vertex, offsets, items);
        std::vector<std::uint8_t> dup(kept.size(), 0);
        std::vector<std::pair<std::uint64_t, std::uint32_t>> local;
        for (std::size_t v = 0; v + 1 < offsets.size(); ++v) {
            const std::uint32_t b = offsets[v], e = offsets[v + 1];
            if (e - b < 2) continue;
            local.clear();
            for (std::uint32_t k = b; k < e; ++k) {
                auto t = tri[kept[items[k]]];
                std::sort(t.begin(), t.end());
                local.emplace_back((std::uint64_t{t[1]} << 32) | t[2], items[k]);
            }
            std::sort(local.begin(), local.end());
            for (std::size_t k = 1; k < local.size(); ++k) {
                if (local[k].first == local[k - 1].first) dup[local[k].second] = 1;
            }
        }
        std::size_t w = 0;
        for (std::size_t k = 0; k < kept.size(); ++k) {
            if (dup[k]) {
                ++rep.duplicate_facets_removed;
            } else {
                kept[w++] = kept[k];
            }
        }
        kept.resize(w);
    }
    const std::size_t nf = kept.size();
    const std::size_t nh = 3 * nf;

    // 4. Compact the vertices to those the kept facets use (in vertex order).
    std::vector<std::uint32_t> corner(nh);
    {
        std::vector<std::uint32_t> remap(vpos.size(), kNone);
        for (std::size_t f = 0; f < nf; ++f) {
            for (std::uint32_t v : tri[kept[f]]) remap[v] = 0;
        }
        std::uint32_t nv = 0;
        for (std::size_t v = 0; v < vpos.size(); ++v) {
            if (remap[v] != kNone) {
                vpos[nv] = vpos[v];
                remap[v] = nv++;
            }
        }
        rep.unreferenced_vertices = vpos.size() - nv;
        vpos.resize(nv);
        vpos.shrink_to_fit();
        for (std::size_t f = 0; f < nf; ++f) {
            const auto& t = tri[kept[f]];
            for (int k = 0; k < 3; ++k) corner[3 * f + k] = remap[t[k]];
        }
    }
    tri = {};
    const std::size_t nv = vpos.size();
    report_progress("clean", 1.0);

    // 5. Pair half-edges into edges. Half-edge h runs corner[h] -> corner[next(h)].
    report_progress("pair", 0.0);
    auto hnext = [](std::size_t h) { return h % 3 == 2 ? h - 2 : h + 1; };
    std::vector<std::uint32_t> mate(nh, kNone);
    {
        std::vector<std::uint32_t> offsets, items;
        auto low = [&](std::size_t h) { return std::min(corner[h], corner[hnext(h)]); };
        bucket_by_key(nh, nv, low, offsets, items);
        std::vector<std::pair<std::uint32_t, std::uint32_t>> local;  // (high vertex, half-edge)
        struct Around {
            double angle;
            std::uint32_t h;
            bool forward;  // runs low -> high
        };
        std::vector<Around> around;
        for (std::size_t v = 0; v < nv; ++v) {
            const std::uint32_t b = offsets[v], e = offsets[v + 1];
            local.clear();
            for (std::uint32_t k = b; k < e; ++k) {
                const std::uint32_t h = items[k];
                local.emplace_back(std::max(corner[h], corner[hnext(h)]), h);
            }
            std::sort(local.begin(), local.end());
            for (std::size_t s = 0; s < local.size();) {
                std::size_t t = s + 1;
                while (t < local.size() && local[t].first == local[s].first) ++t;
                const std::size_t k = t - s;
                if (k == 2) {
                    mate[local[s].second] = local[s + 1].second;
                    mate[local[s + 1].second] = local[s].second;
                } else if (k > 2) {
                    // Non-manifold edge: order its facets by angle around the edge and pair
                    // each facet running high -> low with the next one running low -> high
                    // (counter-clockwise about low -> high): those bound one wedge of
                    // material of a consistently oriented solid, so two solids sharing an
                    // edge come apart.
                    ++rep.nonmanifold_edges;
                    const Vec3 p0 = vpos[v];
                    const Vec3 axis = normalized(vpos[local[s].first] - p0);
                    const Vec3 helper = std::abs(axis.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
                    const Vec3 b1 = normalized(cross(axis, helper));
                    const Vec3 b2 = cross(axis, b1);
                    around.clear();
                    for (std::size_t q = s; q < t; ++q) {
                        const std::uint32_t h = local[q].second;
                        const std::uint32_t third = corner[hnext(hnext(h))];
                        const Vec3 r = vpos[third] - p0;
                        around.push_back({std::atan2(dot(r, b2), dot(r, b1)), h, corner[h] == v});
                    }
                    std::sort(around.begin(), around.end(), [](const Around& x, const Around& y) {
                        return x.angle != y.angle ? x.angle < y.angle : x.h < y.h;
                    });
                    std::size_t best_offset = 0;
                    std::size_t best_score = 0;
                    for (std::size_t off = 0; off < 2 && off < k; ++off) {
                        std::size_t score = 0;
                        for (std::size_t q = 0; q + 1 < k; q += 2) {
                            const Around& x = around[(off + q) % k];
                            const Around& y = around[(off + q + 1) % k];
                            score += (!x.forward && y.forward) ? 1 : 0;
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
                }
                s = t;
            }
        }
    }
    report_progress("pair", 1.0);

    // 6. Orientation: breadth-first over each component in facet order; a neighbour across
    // an edge both facets run the same way must be flipped relative to the current one.
    report_progress("orient", 0.0);
    std::vector<std::uint8_t> flip(nf, 0);
    std::vector<std::uint32_t> comp(nf, kNone);
    std::vector<std::uint32_t> comp_start;  // first facet (in BFS order) of each component
    std::vector<std::uint32_t> bfs;
    bfs.reserve(nf);
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
    comp_start.push_back(static_cast<std::uint32_t>(bfs.size()));
    const std::size_t num_comp = comp_start.size() - 1;
    if (options.orient) {
        // Keep the majority's orientation: flip the minority of each component.
        for (std::size_t c = 0; c < num_comp; ++c) {
            const std::uint32_t b = comp_start[c], e = comp_start[c + 1];
            std::size_t flipped = 0;
            for (std::uint32_t q = b; q < e; ++q) flipped += flip[bfs[q]];
            if (2 * flipped > e - b) {
                for (std::uint32_t q = b; q < e; ++q) flip[bfs[q]] ^= 1;
                flipped = (e - b) - flipped;
            }
            rep.flipped_facets += flipped;
        }
        // Turn closed components outward: positive signed volume (about the box center, for
        // precision).
        const Vec3 center = box.empty() ? Vec3{} : 0.5 * (box.min + box.max);
        for (std::size_t c = 0; c < num_comp; ++c) {
            const std::uint32_t b = comp_start[c], e = comp_start[c + 1];
            bool closed = true;
            double volume6 = 0;
            for (std::uint32_t q = b; q < e; ++q) {
                const std::uint32_t f = bfs[q];
                for (int k = 0; k < 3; ++k) closed &= mate[3 * f + k] != kNone;
                const Vec3 p0 = vpos[corner[3 * f]] - center;
                Vec3 p1 = vpos[corner[3 * f + 1]] - center;
                Vec3 p2 = vpos[corner[3 * f + 2]] - center;
                if (flip[f]) std::swap(p1, p2);
                volume6 += dot(p0, cross(p1, p2));
            }
            if (closed && volume6 < 0) {
                ++rep.components_turned_outward;
                for (std::uint32_t q = b; q < e; ++q) flip[bfs[q]] ^= 1;
            }
        }
    } else {
        std::fill(flip.begin(), flip.end(), 0);
    }
    bfs = {};
    comp = {};
    report_progress("orient", 1.0);

    // 7. The half-edge columns. Flipping facet (v0 v1 v2) to (v0 v2 v1) moves its half-edge
    // in slot i to slot 2 - i.
    report_progress("finish", 0.0);
    Mesh& mesh = out.mesh;
    mesh.origin_.resize(nh);
    mesh.twin_.resize(nh);
    auto slot = [&](std::uint32_t h) -> std::uint32_t {
        const std::uint32_t f = h / 3, i = h % 3;
        return flip[f] ? 3 * f + (2 - i) : h;
    };
    for_chunks(nf, [&](std::size_t b, std::size_t e) {
        for (std::size_t f = b; f < e; ++f) {
            const std::uint32_t* c = &corner[3 * f];
            std::uint32_t* o = &mesh.origin_[3 * f];
            if (flip[f]) {
                o[0] = c[0];
                o[1] = c[2];
                o[2] = c[1];
            } else {
                o[0] = c[0];
                o[1] = c[1];
                o[2] = c[2];
            }
            for (int k = 0; k < 3; ++k) {
                const auto h = static_cast<std::uint32_t>(3 * f + k);
                mesh.twin_[slot(h)] = mate[h] == kNone ? kNone : slot(mate[h]);
            }
        }
    });
    mate = {};
    corner = {};
    flip = {};

    // 8. Split non-manifold vertices: every fan of half-edges around a vertex beyond its
    // first gets a vertex of its own. The outgoing half-edge of a vertex on a boundary is the
    // one without a twin, so that boundary loops can be walked.
    {
        auto& origin = mesh.origin_;
        const auto& twin = mesh.twin_;
        auto nxt = [](std::uint32_t h) { return h % 3 == 2 ? h - 2 : h + 1; };
        auto prv = [](std::uint32_t h) { return h % 3 == 0 ? h + 2 : h - 1; };
        std::vector<std::uint8_t> seen(nh, 0);
        std::vector<std::uint8_t> has_fan(nv, 0);
        std::vector<std::uint8_t> counted(nv, 0);
        mesh.outgoing_.assign(nv, kNone);
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
    mesh.source_face_ = std::move(kept);
    if (attrs) {
        mesh.color_.resize(nf);
        mesh.cut_.resize(nf);
        mesh.surface_.resize(nf);
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

Result<BuildResult> build_mesh(const TriangleSoup& soup, const HealOptions& options,
                               const ProgressFn& progress) {
    return MeshBuilder::build(soup, options, progress);
}

}  // namespace ncrev
