#include "test_meshes.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>

namespace ncrev::test {

Indexed cube(Vec3 o, double s) {
    Indexed m;
    for (int i = 0; i < 8; ++i) {
        m.points.push_back({o.x + s * (i & 1), o.y + s * ((i >> 1) & 1), o.z + s * ((i >> 2) & 1)});
    }
    // Vertex i has x = bit0, y = bit1, z = bit2. Faces counter-clockwise seen from outside.
    m.triangles = {{0, 2, 1}, {1, 2, 3},   // z = 0 (normal -z)
                   {4, 5, 6}, {5, 7, 6},   // z = 1
                   {0, 1, 4}, {1, 5, 4},   // y = 0
                   {2, 6, 3}, {3, 6, 7},   // y = 1
                   {0, 4, 2}, {2, 4, 6},   // x = 0
                   {1, 3, 5}, {3, 7, 5}};  // x = 1
    return m;
}

Indexed icosphere(double radius, int level, Vec3 center) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<Vec3> p = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                           {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                           {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    std::vector<Tri> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                          {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                          {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                          {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
    for (Vec3& v : p) v = normalized(v);
    for (int l = 0; l < level; ++l) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
        auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::minmax(a, b);
            auto it = mid.find(key);
            if (it != mid.end()) return it->second;
            p.push_back(normalized(p[a] + p[b]));
            const auto id = static_cast<std::uint32_t>(p.size() - 1);
            mid.emplace(key, id);
            return id;
        };
        std::vector<Tri> g;
        for (const Tri& tr : f) {
            const std::uint32_t a = midpoint(tr[0], tr[1]), b = midpoint(tr[1], tr[2]),
                                c = midpoint(tr[2], tr[0]);
            g.push_back({tr[0], a, c});
            g.push_back({tr[1], b, a});
            g.push_back({tr[2], c, b});
            g.push_back({a, b, c});
        }
        f.swap(g);
    }
    Indexed m;
    for (const Vec3& v : p) m.points.push_back(center + radius * v);
    m.triangles = f;
    return m;
}

Indexed mobius(int n) {
    Indexed m;
    const double pi = std::acos(-1.0);
    for (int i = 0; i < n; ++i) {
        const double u = 2 * pi * i / n;
        for (int s = -1; s <= 1; s += 2) {
            const double w = 0.3 * s;
            m.points.push_back({(1 + w * std::cos(u / 2)) * std::cos(u),
                                (1 + w * std::cos(u / 2)) * std::sin(u), w * std::sin(u / 2)});
        }
    }
    for (int i = 0; i < n; ++i) {
        const auto a = static_cast<std::uint32_t>(2 * i), b = a + 1;
        std::uint32_t c = static_cast<std::uint32_t>(2 * ((i + 1) % n)), d = c + 1;
        if (i == n - 1) std::swap(c, d);  // the half twist
        m.triangles.push_back({a, c, b});
        m.triangles.push_back({b, c, d});
    }
    return m;
}

TriangleSoup to_bucket(const Indexed& m) {
    TriangleSoup s;
    for (const Tri& t : m.triangles) {
        const auto i = static_cast<std::uint32_t>(s.points.size());
        for (std::uint32_t v : t) s.points.push_back(m.points[v]);
        s.triangles.push_back({i, i + 1, i + 2});
    }
    return s;
}

TriangleSoup to_indexed_soup(const Indexed& m) {
    TriangleSoup s;
    s.format = InputFormat::kSre;
    s.points = m.points;
    s.triangles = m.triangles;
    return s;
}

Indexed merge(const Indexed& a, const Indexed& b) {
    Indexed m = a;
    const auto off = static_cast<std::uint32_t>(a.points.size());
    m.points.insert(m.points.end(), b.points.begin(), b.points.end());
    for (Tri t : b.triangles) m.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
    return m;
}

void rigid_motion(TriangleSoup& soup, double angle, Vec3 translation) {
    const Vec3 k = normalized({1, 2, 3});
    const double c = std::cos(angle), s = std::sin(angle);
    for (Vec3& p : soup.points) {
        // Rodrigues' rotation formula.
        p = c * p + s * cross(k, p) + (1 - c) * dot(k, p) * k + translation;
    }
}

namespace {
std::vector<std::uint32_t> permutation(std::size_t n, std::uint64_t seed) {
    std::vector<std::uint32_t> perm(n);
    std::iota(perm.begin(), perm.end(), 0u);
    std::uint64_t x = seed * 0x9E3779B97F4A7C15ull + 1;
    for (std::size_t i = n; i > 1; --i) {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        std::swap(perm[i - 1], perm[x % i]);
    }
    return perm;
}
}  // namespace

void permute_facets(TriangleSoup& soup, std::uint64_t seed) {
    const auto perm = permutation(soup.triangles.size(), seed);
    auto apply = [&](auto& v) {
        if (v.size() != perm.size()) return;
        auto copy = v;
        for (std::size_t i = 0; i < perm.size(); ++i) v[i] = copy[perm[i]];
    };
    apply(soup.triangles);
    apply(soup.color);
    apply(soup.cut);
    apply(soup.surface);
}

void permute_points(TriangleSoup& soup, std::uint64_t seed) {
    const auto perm = permutation(soup.points.size(), seed);  // new i holds old perm[i]
    std::vector<std::uint32_t> inv(perm.size());
    for (std::size_t i = 0; i < perm.size(); ++i) inv[perm[i]] = static_cast<std::uint32_t>(i);
    auto copy = soup.points;
    for (std::size_t i = 0; i < perm.size(); ++i) soup.points[i] = copy[perm[i]];
    for (auto& t : soup.triangles) {
        for (auto& v : t) v = inv[v];
    }
}

std::vector<std::byte> bytes_of(const std::string& s) {
    std::vector<std::byte> b(s.size());
    std::memcpy(b.data(), s.data(), s.size());
    return b;
}

}  // namespace ncrev::test
