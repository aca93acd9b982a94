// Peer: CGAL's Efficient RANSAC shape detection (Schnabel, Wahl and Klein 2007; Debian
// libcgal-dev), what a CGAL user would run to find the cylinder or torus in a set of points
// with normals: detection restricted to the one shape type, on the same 120 degree patches as
// BM_Fit (fit_bench.cpp), with CGAL's epsilon set to 6 sigma of the noise. It detects and fits
// (least squares on the inliers); ncrev's fit() only fits a region already known.
#include <cmath>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include "bench_common.h"
#include "peer_cgal_ransac.h"

namespace ncrev::bench {
namespace {

using namespace cgal_ransac;

/// The cylinder (kind 0) or torus (kind 1) patch of fit_bench.cpp, as CGAL points.
Pwns patch(int kind, std::size_t count) {
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.003);
    constexpr double kArc = 2.0 * std::numbers::pi / 3;
    Pwns out;
    for (std::size_t i = 0; i < count; ++i) {
        const double u = uni(rng), v = uni(rng), a = kArc * u;
        double q[3], n[3];
        if (kind == 0) {
            n[0] = std::cos(a), n[1] = std::sin(a), n[2] = 0;
            q[0] = 10 * n[0], q[1] = 10 * n[1], q[2] = 30 * v;
        } else {
            const double b = std::numbers::pi * (v - 0.5);
            n[0] = std::cos(b) * std::cos(a), n[1] = std::cos(b) * std::sin(a), n[2] = std::sin(b);
            q[0] = 25 * std::cos(a) + 6 * n[0], q[1] = 25 * std::sin(a) + 6 * n[1], q[2] = 6 * n[2];
        }
        out.emplace_back(
            K::Point_3(q[0] + 30 + noise(rng), q[1] - 20 + noise(rng), q[2] + 10 + noise(rng)),
            K::Vector_3(n[0], n[1], n[2]));
    }
    return out;
}

template <class Shape>
void run(benchmark::State& state, int kind) {
    Pwns points = patch(kind, static_cast<std::size_t>(state.range(0)));
    Ransac::Parameters p;
    p.probability = 0.01;
    p.min_points = points.size() / 2;
    p.epsilon = 0.02;  // about 6 sigma, as ncrev's B-spline bench and kind selection use
    p.cluster_epsilon = 1.0;
    p.normal_threshold = 0.9;
    std::size_t found = 0;
    double radius = 0;
    for (auto _ : state) {
        Ransac ransac;
        ransac.set_input(points);
        ransac.template add_shape_factory<Shape>();
        ransac.detect(p);
        found = ransac.shapes().size();
        if (found > 0) {
            if (auto s = dynamic_cast<const Shape*>(ransac.shapes().begin()->get())) {
                if constexpr (std::is_same_v<Shape, CGAL::Shape_detection::Cylinder<Traits>>) {
                    radius = s->radius();
                } else {
                    radius = s->major_radius();
                }
            }
        }
    }
    state.counters["shapes"] = static_cast<double>(found);
    state.counters["radius"] = radius;
}

void BM_Peer_Cgal_RansacCylinder(benchmark::State& state) {
    run<CGAL::Shape_detection::Cylinder<Traits>>(state, 0);
}
void BM_Peer_Cgal_RansacTorus(benchmark::State& state) {
    run<CGAL::Shape_detection::Torus<Traits>>(state, 1);
}
BENCHMARK(BM_Peer_Cgal_RansacCylinder)
    ->Arg(10'000)
    ->Arg(100'000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_Peer_Cgal_RansacTorus)
    ->Arg(10'000)
    ->Arg(100'000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace ncrev::bench
