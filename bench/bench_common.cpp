#include "bench_common.h"

#include <malloc.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <map>
#include <new>

namespace {
std::atomic<std::size_t> g_now{0};
std::atomic<std::size_t> g_peak{0};

void* counted_alloc(std::size_t n) {
    void* p = std::malloc(n == 0 ? 1 : n);
    if (p == nullptr) throw std::bad_alloc();
    const std::size_t now = g_now.fetch_add(malloc_usable_size(p)) + malloc_usable_size(p);
    std::size_t peak = g_peak.load();
    while (now > peak && !g_peak.compare_exchange_weak(peak, now)) {
    }
    return p;
}
void counted_free(void* p) {
    if (p == nullptr) return;
    g_now.fetch_sub(malloc_usable_size(p));
    std::free(p);
}
}  // namespace

void* operator new(std::size_t n) { return counted_alloc(n); }
void* operator new[](std::size_t n) { return counted_alloc(n); }
void operator delete(void* p) noexcept { counted_free(p); }
void operator delete[](void* p) noexcept { counted_free(p); }
void operator delete(void* p, std::size_t) noexcept { counted_free(p); }
void operator delete[](void* p, std::size_t) noexcept { counted_free(p); }

namespace ncrev::bench {

std::size_t heap_now() { return g_now.load(); }
std::size_t heap_peak() { return g_peak.load(); }
void heap_reset_peak() { g_peak.store(g_now.load()); }

const TriangleSoup& torus_soup(std::size_t facets) {
    static std::map<std::size_t, TriangleSoup> cache;
    auto it = cache.find(facets);
    if (it != cache.end()) return it->second;
    // nu:nv = 2:1 keeps the triangles well shaped on a torus with R/r = 2.4.
    const auto nv = static_cast<std::size_t>(std::sqrt(static_cast<double>(facets) / 4.0));
    const std::size_t nu = facets / (2 * nv);
    const double pi = std::acos(-1.0);
    const double big = 60.0, small = 25.0;
    std::vector<Vec3> grid(nu * nv);
    for (std::size_t i = 0; i < nu; ++i) {
        const double u = 2 * pi * static_cast<double>(i) / static_cast<double>(nu);
        for (std::size_t j = 0; j < nv; ++j) {
            const double v = 2 * pi * static_cast<double>(j) / static_cast<double>(nv);
            // float32-exact, as the points come back from an STL
            grid[i * nv + j] = {static_cast<float>((big + small * std::cos(v)) * std::cos(u)),
                                static_cast<float>((big + small * std::cos(v)) * std::sin(u)),
                                static_cast<float>(small * std::sin(v))};
        }
    }
    TriangleSoup s;
    s.points.reserve(6 * nu * nv);
    s.triangles.reserve(2 * nu * nv);
    auto add = [&](std::size_t a, std::size_t b, std::size_t c) {
        const auto k = static_cast<std::uint32_t>(s.points.size());
        s.points.push_back(grid[a]);
        s.points.push_back(grid[b]);
        s.points.push_back(grid[c]);
        s.triangles.push_back({k, k + 1, k + 2});
    };
    for (std::size_t i = 0; i < nu; ++i) {
        for (std::size_t j = 0; j < nv; ++j) {
            const std::size_t a = i * nv + j, b = ((i + 1) % nu) * nv + j;
            const std::size_t c = ((i + 1) % nu) * nv + (j + 1) % nv, d = i * nv + (j + 1) % nv;
            add(a, b, c);
            add(a, c, d);
        }
    }
    return cache.emplace(facets, std::move(s)).first->second;
}

const Mesh& torus_mesh(std::size_t facets) {
    static std::map<std::size_t, Mesh> cache;
    auto it = cache.find(facets);
    if (it == cache.end()) {
        it = cache.emplace(facets, build_mesh(torus_soup(facets)).value().mesh).first;
    }
    return it->second;
}

const TriangleSoup& box_grid_soup(std::size_t facets) {
    static std::map<std::size_t, TriangleSoup> cache;
    auto it = cache.find(facets);
    if (it != cache.end()) return it->second;
    const auto n = std::max<std::size_t>(
        1, static_cast<std::size_t>(std::sqrt(static_cast<double>(facets) / 12.0)));
    const Vec3 size{100, 60, 40};
    TriangleSoup s;
    // Face (axis a, side): a grid over the two other axes, counter-clockwise from outside.
    for (int a = 0; a < 3; ++a) {
        for (int side = 0; side < 2; ++side) {
            const int u = (a + 1) % 3, v = (a + 2) % 3;
            auto corner = [&](std::size_t i, std::size_t j) {
                Vec3 p;
                p[a] = side ? size[a] : 0.0;
                p[u] = size[u] * static_cast<double>(i) / static_cast<double>(n);
                p[v] = size[v] * static_cast<double>(j) / static_cast<double>(n);
                return Vec3{static_cast<float>(p.x), static_cast<float>(p.y),
                            static_cast<float>(p.z)};
            };
            for (std::size_t i = 0; i < n; ++i) {
                for (std::size_t j = 0; j < n; ++j) {
                    Vec3 q[4] = {corner(i, j), corner(i + 1, j), corner(i + 1, j + 1),
                                 corner(i, j + 1)};
                    if (!side) std::swap(q[1], q[3]);  // the low side faces the other way
                    for (int t = 0; t < 2; ++t) {
                        const auto k = static_cast<std::uint32_t>(s.points.size());
                        s.points.push_back(q[0]);
                        s.points.push_back(q[1 + t]);
                        s.points.push_back(q[2 + t]);
                        s.triangles.push_back({k, k + 1, k + 2});
                    }
                }
            }
        }
    }
    return cache.emplace(facets, std::move(s)).first->second;
}

std::filesystem::path box_grid_file(std::size_t facets) {
    const auto path = std::filesystem::temp_directory_path() /
                      ("ncrev_bench_box_" + std::to_string(facets) + ".stl");
    const auto& s = box_grid_soup(facets);
    const auto bytes = encode_stl_binary(s.points, s.triangles, "box");
    if (!std::filesystem::exists(path) || std::filesystem::file_size(path) != bytes.size()) {
        if (!write_file_atomic(path, bytes).ok()) std::abort();
    }
    return path;
}

const std::vector<std::byte>& stl_binary_bytes(std::size_t facets) {
    static std::map<std::size_t, std::vector<std::byte>> cache;
    auto it = cache.find(facets);
    if (it != cache.end()) return it->second;
    const auto& s = torus_soup(facets);
    return cache.emplace(facets, encode_stl_binary(s.points, s.triangles, "torus")).first->second;
}

const std::string& stl_ascii_text(std::size_t facets) {
    static std::map<std::size_t, std::string> cache;
    auto it = cache.find(facets);
    if (it != cache.end()) return it->second;
    const auto& s = torus_soup(facets);
    return cache.emplace(facets, encode_stl_ascii(s.points, s.triangles, "torus")).first->second;
}

const std::string& sre_text(std::size_t facets) {
    static std::map<std::size_t, std::string> cache;
    auto it = cache.find(facets);
    if (it != cache.end()) return it->second;
    // The SRE view shares vertices: weld the soup's points by value first.
    const auto& s = torus_soup(facets);
    TriangleSoup idx;
    idx.format = InputFormat::kSre;
    std::map<std::tuple<double, double, double>, std::uint32_t> ids;
    for (const auto& t : s.triangles) {
        std::array<std::uint32_t, 3> tri{};
        for (int k = 0; k < 3; ++k) {
            const Vec3 p = s.points[t[k]];
            auto [pos, fresh] = ids.emplace(std::make_tuple(p.x, p.y, p.z),
                                            static_cast<std::uint32_t>(idx.points.size()));
            if (fresh) idx.points.push_back(p);
            tri[k] = pos->second;
        }
        idx.triangles.push_back(tri);
        idx.color.push_back(0xFF0000);
        idx.cut.push_back(static_cast<std::int64_t>(idx.triangles.size() % 97));
        idx.surface.push_back(-1);
    }
    return cache.emplace(facets, encode_sre(idx)).first->second;
}

std::filesystem::path stl_binary_file(std::size_t facets) {
    const auto path = std::filesystem::temp_directory_path() /
                      ("ncrev_bench_torus_" + std::to_string(facets) + ".stl");
    if (!std::filesystem::exists(path) ||
        std::filesystem::file_size(path) != stl_binary_bytes(facets).size()) {
        if (!write_file_atomic(path, stl_binary_bytes(facets)).ok()) std::abort();
    }
    return path;
}

}  // namespace ncrev::bench
