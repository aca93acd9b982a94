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
    return 0;
}
