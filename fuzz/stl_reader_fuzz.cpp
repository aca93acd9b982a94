// Fuzz target: the STL reader (ASCII and binary) on arbitrary bytes. It must return a mesh or
// a typed error, never crash or read out of bounds; an accepted mesh must be well formed.
#include <cstdlib>

#include "ncrev/io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    auto r = ncrev::read_stl({reinterpret_cast<const std::byte*>(data), size}, "fuzz.stl");
    if (r.ok()) {
        for (const auto& t : r->triangles) {
            for (std::uint32_t v : t) {
                if (v >= r->points.size()) std::abort();
            }
        }
        for (const auto& p : r->points) {
            if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) std::abort();
        }
    } else if (r.error().message.empty()) {
        std::abort();
    }
    // Welding while reading must accept exactly the same files and describe the same facets.
    ncrev::ReadOptions weld;
    weld.weld_exact = true;
    auto w = ncrev::read_stl({reinterpret_cast<const std::byte*>(data), size}, "fuzz.stl", weld);
    if (w.ok() != r.ok()) std::abort();
    if (w.ok()) {
        if (w->num_facets() != r->num_facets()) std::abort();
        for (std::size_t f = 0; f < r->num_facets(); ++f) {
            for (int k = 0; k < 3; ++k) {
                const auto a = r->points[r->triangles[f][k]], b = w->points[w->triangles[f][k]];
                if (!(a == b)) std::abort();  // -0 == +0
            }
        }
    }
    return 0;
}
