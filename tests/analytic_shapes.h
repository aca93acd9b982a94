// Surfaces with known curvature, meshed isotropically (near-equilateral triangles, optionally
// jittered along the surface) or the way CAD systems do (BRepMesh of the OpenCASCADE
// primitive: long thin triangles), for the curvature and fitting tests and the curvature study.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <utility>

#include "test_meshes.h"

namespace ncrev::test {

/// A mesh of a surface and the exact principal curvatures (k1 >= k2, positive where convex
/// seen from the side the facets face) at any point of that surface.
struct AnalyticMesh {
    std::string name;
    Indexed mesh;
    std::function<std::pair<double, double>(Vec3)> curvature;
    /// False for points too close to the patch border for a curvature estimate to be judged
    /// (the border of an open patch, a cone's apex, a sphere's poles in a CAD mesh).
    std::function<bool(Vec3)> interior;
};

/// How to mesh isotropically: about `facets` facets; `jitter` moves every vertex along the
/// surface by up to that fraction of the local spacing (0: a regular staggered grid).
struct IsoOptions {
    std::uint64_t facets = 50000;
    double jitter = 0.0;
    std::uint64_t seed = 1;
    /// Spacing along the profile over spacing around the axis: 1 is isotropic; larger gives
    /// the long thin triangles of a CAD tessellation (rings far apart, many points per ring).
    double aspect = 1.0;
};

/// Sphere of radius r at the origin (closed; poles closed by fans).
AnalyticMesh iso_sphere(double r, const IsoOptions& o);
/// Open cylinder of radius r and height h about the z axis.
AnalyticMesh iso_cylinder(double r, double h, const IsoOptions& o);
/// Open cone frustum about the z axis: radius r0 at z = 0 to r1 at z = h.
AnalyticMesh iso_cone(double r0, double r1, double h, const IsoOptions& o);
/// Torus about the z axis, major radius R, minor radius r (closed).
AnalyticMesh iso_torus(double R, double r, const IsoOptions& o);
/// The saddle z = (x^2 - y^2) / (2a) over the disc of radius `extent`.
AnalyticMesh iso_saddle(double a, double extent, const IsoOptions& o);

/// The same mesh with every facet reversed: curvatures change sign (a concave surface).
AnalyticMesh inside_out(AnalyticMesh m);

/// Rounds every coordinate to float32, as a binary STL stores it.
void round_to_float(std::span<Vec3> points);
/// Moves every vertex by a Gaussian of standard deviation sigma in each coordinate.
void add_noise(Indexed& m, double sigma, std::uint64_t seed);

/// Tiny deterministic PRNG (splitmix64), uniform in [0, 1).
class Rng {
   public:
    explicit Rng(std::uint64_t seed) : state_(seed) {}
    double uniform();
    double gaussian();

   private:
    std::uint64_t state_;
};

}  // namespace ncrev::test
