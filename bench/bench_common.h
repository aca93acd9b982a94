// Shared by the benchmarks: generated meshes (cached per size), files on disk, and a heap
// counter (global operator new/delete) for peak-memory figures.
#pragma once

#include <benchmark/benchmark.h>

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "ncrev/io.h"
#include "ncrev/mesh.h"

namespace ncrev::bench {

/// A closed torus grid (R = 60 mm, r = 25 mm) with about `facets` facets (2·nu·nv), written
/// facet by facet as a CAD exporter does. Cached.
const TriangleSoup& torus_soup(std::size_t facets);
/// That torus built into a mesh (build_mesh() with its defaults). Cached.
const Mesh& torus_mesh(std::size_t facets);
/// A prismatic part: a 100 x 60 x 40 mm box whose six faces are each a grid of n x n quads
/// (about `facets` facets), as a fine simulator mesh of a planar part is. Cached.
const TriangleSoup& box_grid_soup(std::size_t facets);
/// The box grid as a binary STL on disk (for the FreeCAD comparison).
std::filesystem::path box_grid_file(std::size_t facets);

/// Encodings of the same mesh, cached.
const std::vector<std::byte>& stl_binary_bytes(std::size_t facets);
const std::string& stl_ascii_text(std::size_t facets);
const std::string& sre_text(std::size_t facets);
/// The binary STL on disk (in the temp folder), written once.
std::filesystem::path stl_binary_file(std::size_t facets);

/// Heap accounting (this binary replaces global operator new/delete).
std::size_t heap_now();
std::size_t heap_peak();
void heap_reset_peak();

}  // namespace ncrev::bench
