// Meshes with known answers for the tests: cubes, spheres, and helpers to turn an indexed
// mesh into an STL-like facet soup, move it, and permute it.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "ncrev/io.h"

namespace ncrev::test {

using Tri = std::array<std::uint32_t, 3>;

struct Indexed {
    std::vector<Vec3> points;
    std::vector<Tri> triangles;
};

/// An axis-aligned cube [o, o + s]^3, 8 vertices, 12 facets, outward.
Indexed cube(Vec3 o = {0, 0, 0}, double s = 1.0);
/// An icosphere of `level` subdivisions (20·4^level facets), outward.
Indexed icosphere(double radius, int level, Vec3 center = {0, 0, 0});
/// A Möbius band of n quads (2n facets): open and non-orientable.
Indexed mobius(int n);

/// The STL view: three fresh points per facet, as a binary STL reader returns.
TriangleSoup to_bucket(const Indexed& m);
/// The SRE view: shared vertices as given.
TriangleSoup to_indexed_soup(const Indexed& m);
/// Concatenates two meshes.
Indexed merge(const Indexed& a, const Indexed& b);

/// Applies a rotation (about axis (1,2,3) by `angle`) and a translation to every point.
void rigid_motion(TriangleSoup& soup, double angle, Vec3 translation);
/// Reorders facets (and for indexed soups, vertices) with a fixed pseudo-random permutation.
void permute_facets(TriangleSoup& soup, std::uint64_t seed);
void permute_points(TriangleSoup& soup, std::uint64_t seed);

/// Bytes of a string, for readers.
std::vector<std::byte> bytes_of(const std::string& s);

}  // namespace ncrev::test
