// Fuzz target: the SRE reader on arbitrary bytes. An accepted file must satisfy every rule of
// the format page; a rejected one must name a line.
#include <cstdlib>

#include "ncrev/io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    auto r = ncrev::read_sre({reinterpret_cast<const std::byte*>(data), size}, "fuzz.sre");
    if (!r.ok()) {
        if (size > 0 && r.error().line < 1) std::abort();
        return 0;
    }
    const auto& s = *r;
    if (s.color.size() != s.num_facets() || s.surface.size() != s.num_facets()) std::abort();
    for (std::size_t f = 0; f < s.num_facets(); ++f) {
        const auto& t = s.triangles[f];
        for (std::uint32_t v : t) {
            if (v >= s.points.size()) std::abort();
        }
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) std::abort();
        if (s.surface[f] < -1 || s.surface[f] >= static_cast<std::int64_t>(s.surfaces.size()))
            std::abort();
    }
    // What was accepted must round-trip through the writer.
    const std::string text = ncrev::encode_sre(s);
    auto again = ncrev::read_sre({reinterpret_cast<const std::byte*>(text.data()), text.size()});
    if (!again.ok() || again->points != s.points || again->triangles != s.triangles) std::abort();
    return 0;
}
