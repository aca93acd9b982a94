#include "analytic_shapes.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace ncrev::test {

double Rng::uniform() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return static_cast<double>((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
}

double Rng::gaussian() {
    const double u = std::max(uniform(), 1e-300), v = uniform();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * v);
}

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

/// A profile curve (rho(s), z(s)) in arclength s in [0, length]; revolved about z. The surface
/// faces to the right of the profile's direction in the (rho, z) half plane.
struct Profile {
    double length = 0;
    std::function<std::pair<double, double>(double)> at;
    bool closed = false;  ///< the profile is a closed curve (a torus)
};

/// Spacing of an equilateral mesh of about `facets` facets on a surface of area `area`.
double spacing(double area, std::uint64_t facets) {
    return std::sqrt(4.0 * area / (std::sqrt(3.0) * static_cast<double>(facets)));
}

Indexed revolve(const Profile& prof, double h, double jitter, std::uint64_t seed,
                double aspect = 1.0) {
    Rng rng(seed);
    const double ds_nominal = aspect * h * std::sqrt(3.0) / 2.0;
    const int steps = std::max(1, static_cast<int>(std::lround(prof.length / ds_nominal)));
    const double ds = prof.length / steps;
    const int num_rings = prof.closed ? steps : steps + 1;
    Indexed m;
    struct Ring {
        std::vector<std::uint32_t> ids;
        std::vector<double> angle;  // increasing, unwrapped
    };
    std::vector<Ring> rings(static_cast<std::size_t>(num_rings));
    for (int j = 0; j < num_rings; ++j) {
        const bool end = !prof.closed && (j == 0 || j == steps);
        const double s0 = j * ds;
        const double rho0 = prof.at(s0).first;
        Ring& ring = rings[static_cast<std::size_t>(j)];
        if (rho0 <= 1e-12 * prof.length) {  // a pole: one point
            const double z = prof.at(s0).second;
            ring.ids.push_back(static_cast<std::uint32_t>(m.points.size()));
            ring.angle.push_back(0);
            m.points.push_back({0, 0, z});
            continue;
        }
        const int n = std::max(3, static_cast<int>(std::lround(kTwoPi * rho0 / h)));
        const double step = kTwoPi / n;
        const double phase = (j % 2) * 0.5 * step;
        for (int i = 0; i < n; ++i) {
            const double phi = phase + i * step + jitter * (rng.uniform() - 0.5) * step;
            double s = s0;
            if (!end) s += jitter * (rng.uniform() - 0.5) * ds;
            if (prof.closed) s = std::fmod(s + prof.length, prof.length);
            const auto [rho, z] = prof.at(s);
            ring.ids.push_back(static_cast<std::uint32_t>(m.points.size()));
            ring.angle.push_back(phi);
            m.points.push_back({rho * std::cos(phi), rho * std::sin(phi), z});
        }
    }
    auto zip = [&](const Ring& a, const Ring& b) {
        const std::size_t na = a.ids.size(), nb = b.ids.size();
        if (na == 1) {
            for (std::size_t j = 0; j < nb; ++j)
                m.triangles.push_back({a.ids[0], b.ids[(j + 1) % nb], b.ids[j]});
            return;
        }
        if (nb == 1) {
            for (std::size_t i = 0; i < na; ++i)
                m.triangles.push_back({a.ids[i], a.ids[(i + 1) % na], b.ids[0]});
            return;
        }
        // Start b at the point nearest in angle to a's first point.
        std::size_t j0 = 0;
        double best = 1e300;
        for (std::size_t j = 0; j < nb; ++j) {
            double d = std::fabs(std::remainder(b.angle[j] - a.angle[0], kTwoPi));
            if (d < best) best = d, j0 = j;
        }
        auto angle_a = [&](std::size_t i) { return a.angle[i % na] + kTwoPi * double(i / na); };
        const double base_b = a.angle[0] + std::remainder(b.angle[j0] - a.angle[0], kTwoPi);
        auto angle_b = [&](std::size_t j) {
            const std::size_t k = (j0 + j) % nb;
            double x = b.angle[k] - b.angle[j0];
            if (x < 0) x += kTwoPi;
            return base_b + x + kTwoPi * double(j / nb);
        };
        std::size_t i = 0, j = 0;
        while (i < na || j < nb) {
            if (j >= nb || (i < na && angle_a(i + 1) <= angle_b(j + 1))) {
                m.triangles.push_back({a.ids[i % na], a.ids[(i + 1) % na], b.ids[(j0 + j) % nb]});
                ++i;
            } else {
                m.triangles.push_back(
                    {a.ids[i % na], b.ids[(j0 + j + 1) % nb], b.ids[(j0 + j) % nb]});
                ++j;
            }
        }
    };
    for (int j = 0; j + 1 < num_rings; ++j) zip(rings[j], rings[j + 1]);
    if (prof.closed) zip(rings[num_rings - 1], rings[0]);
    return m;
}

}  // namespace

AnalyticMesh iso_sphere(double r, const IsoOptions& o) {
    Profile p;
    p.length = std::numbers::pi * r;
    p.at = [r](double s) { return std::pair{r * std::sin(s / r), -r * std::cos(s / r)}; };
    const double h = spacing(4 * std::numbers::pi * r * r, o.facets);
    AnalyticMesh out{"sphere", revolve(p, h, o.jitter, o.seed), nullptr, nullptr};
    out.curvature = [r](Vec3) { return std::pair{1.0 / r, 1.0 / r}; };
    // The fans at the poles are not isotropic: judge the rest.
    out.interior = [r, h](Vec3 q) { return std::fabs(q.z) < r - 2 * h; };
    return out;
}

AnalyticMesh iso_cylinder(double r, double height, const IsoOptions& o) {
    Profile p;
    p.length = height;
    p.at = [r](double s) { return std::pair{r, s}; };
    const double h = spacing(kTwoPi * r * height, o.facets) / std::sqrt(o.aspect);
    AnalyticMesh out{"cylinder", revolve(p, h, o.jitter, o.seed, o.aspect), nullptr, nullptr};
    out.curvature = [r](Vec3) { return std::pair{1.0 / r, 0.0}; };
    const double margin = 4 * h * o.aspect;
    out.interior = [margin, height](Vec3 q) { return q.z > margin && q.z < height - margin; };
    return out;
}

AnalyticMesh iso_cone(double r0, double r1, double height, const IsoOptions& o) {
    Profile p;
    const double len = std::hypot(r1 - r0, height);
    p.length = len;
    p.at = [=](double s) { return std::pair{r0 + (r1 - r0) * s / len, height * s / len}; };
    const double h = spacing(std::numbers::pi * (r0 + r1) * len, o.facets);
    AnalyticMesh out{"cone", revolve(p, h, o.jitter, o.seed), nullptr, nullptr};
    const double cos_alpha = height / len;
    out.curvature = [cos_alpha](Vec3 q) {
        return std::pair{cos_alpha / std::hypot(q.x, q.y), 0.0};
    };
    out.interior = [h, height](Vec3 q) { return q.z > 4 * h && q.z < height - 4 * h; };
    return out;
}

AnalyticMesh iso_torus(double R, double r, const IsoOptions& o) {
    Profile p;
    p.length = kTwoPi * r;
    p.closed = true;
    p.at = [R, r](double s) {
        const double v = s / r;
        return std::pair{R + r * std::cos(v), r * std::sin(v)};
    };
    const double h = spacing(4 * std::numbers::pi * std::numbers::pi * R * r, o.facets);
    AnalyticMesh out{"torus", revolve(p, h, o.jitter, o.seed), nullptr, nullptr};
    out.curvature = [R, r](Vec3 q) {
        const double rho = std::hypot(q.x, q.y);
        const double v = std::atan2(q.z, rho - R);
        const double kp = std::cos(v) / rho, km = 1.0 / r;
        return std::pair{std::max(kp, km), std::min(kp, km)};
    };
    out.interior = [](Vec3) { return true; };
    return out;
}

AnalyticMesh iso_saddle(double a, double extent, const IsoOptions& o) {
    Rng rng(o.seed);
    const double h = spacing(std::numbers::pi * extent * extent, o.facets);
    const double dy = h * std::sqrt(3.0) / 2.0;
    const int nx = static_cast<int>(std::ceil(2 * extent / h)) + 2;
    const int ny = static_cast<int>(std::ceil(2 * extent / dy)) + 2;
    Indexed grid;
    auto id = [nx](int i, int j) { return static_cast<std::uint32_t>(j * (nx + 1) + i); };
    for (int j = 0; j <= ny; ++j) {
        for (int i = 0; i <= nx; ++i) {
            double x = -extent - h + i * h + (j % 2) * 0.5 * h;
            double y = -extent - dy + j * dy;
            x += o.jitter * (rng.uniform() - 0.5) * h;
            y += o.jitter * (rng.uniform() - 0.5) * dy;
            grid.points.push_back({x, y, (x * x - y * y) / (2 * a)});
        }
    }
    for (int j = 0; j < ny; ++j) {
        for (int i = 0; i < nx; ++i) {
            // Rows alternate their offset; split each quad along the short diagonal.
            std::uint32_t a0 = id(i, j), a1 = id(i + 1, j), b0 = id(i, j + 1),
                          b1 = id(i + 1, j + 1);
            std::array<Tri, 2> t = j % 2 == 0
                                       ? std::array<Tri, 2>{Tri{a0, a1, b0}, Tri{a1, b1, b0}}
                                       : std::array<Tri, 2>{Tri{a0, b1, b0}, Tri{a0, a1, b1}};
            for (const Tri& tr : t) {
                const Vec3 c = (grid.points[tr[0]] + grid.points[tr[1]] + grid.points[tr[2]]) / 3.0;
                if (c.x * c.x + c.y * c.y <= extent * extent) grid.triangles.push_back(tr);
            }
        }
    }
    // Keep only referenced points (in order) so the mesh has no strays.
    std::vector<std::uint32_t> remap(grid.points.size(), UINT32_MAX);
    Indexed m;
    for (Tri& tr : grid.triangles) {
        for (std::uint32_t& v : tr) {
            if (remap[v] == UINT32_MAX) {
                remap[v] = static_cast<std::uint32_t>(m.points.size());
                m.points.push_back(grid.points[v]);
            }
            v = remap[v];
        }
        m.triangles.push_back(tr);
    }
    AnalyticMesh out{"saddle", std::move(m), nullptr, nullptr};
    out.curvature = [a](Vec3 q) {
        // Monge patch z = f(x, y), normal up; the facets face up. Curvature toward the normal is
        // concave here, hence the sign flip.
        const double fx = q.x / a, fy = -q.y / a, fxx = 1 / a, fyy = -1 / a, fxy = 0;
        const double w = std::sqrt(1 + fx * fx + fy * fy);
        const double E = 1 + fx * fx, F = fx * fy, G = 1 + fy * fy;
        const double L = fxx / w, M = fxy / w, N = fyy / w;
        const double det = E * G - F * F;
        const double K = (L * N - M * M) / det, H = (E * N + G * L - 2 * F * M) / (2 * det);
        const double root = std::sqrt(std::max(0.0, H * H - K));
        return std::pair{-H + root, -H - root};
    };
    out.interior = [extent, h](Vec3 q) { return std::hypot(q.x, q.y) < extent - 4 * h; };
    return out;
}

AnalyticMesh inside_out(AnalyticMesh m) {
    for (Tri& t : m.mesh.triangles) std::swap(t[1], t[2]);
    auto k = m.curvature;
    m.curvature = [k](Vec3 q) {
        const auto [k1, k2] = k(q);
        return std::pair{-k2, -k1};
    };
    m.name = "concave " + m.name;
    return m;
}

void round_to_float(std::span<Vec3> points) {
    for (Vec3& p : points)
        for (int i = 0; i < 3; ++i) p[i] = static_cast<double>(static_cast<float>(p[i]));
}

void add_noise(Indexed& m, double sigma, std::uint64_t seed) {
    Rng rng(seed);
    for (Vec3& p : m.points)
        for (int i = 0; i < 3; ++i) p[i] += sigma * rng.gaussian();
}

}  // namespace ncrev::test
