// STL reader (ASCII and binary). Binary is recognised by its size, 84 + 50·n bytes with n the
// header's facet count, because many binary files begin with the word "solid".
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <bit>
#include <cstring>
#include <optional>

#include "detail/exact_weld.h"
#include "io/text.h"
#include "ncrev/io.h"

namespace ncrev {

namespace {

using io_detail::iequals;
using io_detail::quote;

constexpr std::size_t kStlHeaderBytes = 84;  // 80-byte header + uint32 facet count
constexpr std::size_t kStlRecordBytes = 50;  // normal, 3 vertices (12 float32), uint16 attribute
// Three 32-bit point ids per facet: beyond this many facets the ids would overflow.
constexpr std::uint64_t kMaxFacets = 0xFFFFFFFEull / 3;
// From this many facets a binary STL is welded in two halves at once (see read_binary()):
// below it one pass's table stays in cache, and a second table and the merge cost about what
// the half saves (BM_ReadStlBinaryWelding, built with this at 1 << 30 and at 1 << 16: one pass
// is the faster at 100k facets, two halves by 6 % at 1M and 18 % at 5M; docs/benchmarks.md).
constexpr std::uint64_t kTwoBlockWeldFacets = 1 << 18;

Error make_error(ErrorCode code, std::string_view name, std::string message, std::int64_t line = -1,
                 std::int64_t offset = -1) {
    Error e;
    e.code = code;
    e.path = std::string(name);
    e.message = std::move(message);
    e.line = line;
    e.byte_offset = offset;
    return e;
}

std::uint32_t load_u32(const std::byte* p) {
    std::uint32_t v;
    std::memcpy(&v, p, 4);  // STL is little-endian, as is every platform we build for
    return v;
}

std::uint32_t float_key(float v) {
    const auto b = std::bit_cast<std::uint32_t>(v);
    return b == 0x80000000u ? 0u : b;  // -0 and +0 are the same point
}

/// The welder's distinct points become the soup's points (`input_points` were read).
void take_welded_points(const detail::ExactWelder<std::uint32_t>& welder,
                        std::uint64_t input_points, TriangleSoup& soup) {
    soup.welded_points = input_points - welder.size();
    detail::resize_huge(soup.points, welder.size());
    for (std::size_t c = 0; c < welder.size(); ++c) {
        const auto& k = welder.keys()[c];
        soup.points[c] = {std::bit_cast<float>(k[0]), std::bit_cast<float>(k[1]),
                          std::bit_cast<float>(k[2])};
    }
    soup.points_distinct = true;
}

/// Exact weld of a bucket soup whose points are float32 values (as every STL's are).
void weld_float_points(TriangleSoup& soup) {
    detail::ExactWelder<std::uint32_t> welder(soup.points.size());
    std::vector<std::uint32_t> id;
    detail::resize_huge(id, soup.points.size());
    for (std::size_t i = 0; i < soup.points.size(); ++i) {
        const Vec3 p = soup.points[i];
        id[i] =
            welder.insert({float_key(static_cast<float>(p.x)), float_key(static_cast<float>(p.y)),
                           float_key(static_cast<float>(p.z))});
    }
    for (auto& t : soup.triangles) {
        for (auto& v : t) v = id[v];
    }
    take_welded_points(welder, soup.points.size(), soup);
    soup.points.shrink_to_fit();
}

Result<TriangleSoup> read_binary(std::span<const std::byte> bytes, std::string_view name,
                                 bool weld) {
    const std::uint64_t n = load_u32(bytes.data() + 80);
    if (n > kMaxFacets) {
        return make_error(ErrorCode::kTooLarge, name,
                          "binary STL with " + std::to_string(n) + " facets exceeds the " +
                              std::to_string(kMaxFacets) + " this build can address",
                          -1, 80);
    }
    TriangleSoup soup;
    soup.format = InputFormat::kStlBinary;
    {
        const char* h = reinterpret_cast<const char*>(bytes.data());
        std::size_t len = 0;
        while (len < 80 && h[len] != '\0') ++len;
        std::string_view header(h, len);
        while (!header.empty() && io_detail::is_space(header.back())) header.remove_suffix(1);
        for (char c : header) soup.name += (c >= 0x20 && c < 0x7f) ? c : '?';
    }
    detail::resize_huge(soup.triangles, n);
    const std::byte* rec = bytes.data() + kStlHeaderBytes;
    // The nine coordinates of facet f; an error naming the byte of the first non-finite one.
    auto load = [&](std::uint64_t f, const std::byte* r, float* c) -> std::optional<Error> {
        std::memcpy(c, r + 12, 9 * sizeof(float));
        bool finite = true;
        for (int k = 0; k < 9; ++k) finite &= std::isfinite(c[k]);
        if (finite) return std::nullopt;
        int k = 0;
        while (std::isfinite(c[k])) ++k;
        return make_error(ErrorCode::kBadNumber, name,
                          "facet " + std::to_string(f) + " has a non-finite coordinate", -1,
                          static_cast<std::int64_t>(r - bytes.data()) + 12 + 4 * k);
    };
    if (weld) {
        // Weld while reading: the soup holds each vertex once (a third of the memory of
        // three points per facet) and the keys are the file's own float32 bits.
        // Facets [begin, end) into `welder`, their corners as its classes; the first
        // non-finite coordinate's error, if any.
        auto weld_range = [&](detail::ExactWelder<std::uint32_t>& welder, std::uint64_t begin,
                              std::uint64_t end) -> std::optional<Error> {
            // Prefetch the table slots of the vertices a few facets ahead: a new vertex (one
            // in six) misses the large table, and its cost is a memory round trip otherwise.
            constexpr std::uint64_t kPrefetchFacets = 8;
            const std::byte* r = bytes.data() + kStlHeaderBytes + begin * kStlRecordBytes;
            for (std::uint64_t f = begin; f < end; ++f, r += kStlRecordBytes) {
                float c[9];
                if (auto bad = load(f, r, c)) return bad;
                if (f + kPrefetchFacets < end) {
                    float a[9];
                    std::memcpy(a, r + kPrefetchFacets * kStlRecordBytes + 12, sizeof a);
                    for (int k = 0; k < 3; ++k) {
                        welder.prefetch({float_key(a[3 * k]), float_key(a[3 * k + 1]),
                                         float_key(a[3 * k + 2])});
                    }
                }
                for (int k = 0; k < 3; ++k) {
                    soup.triangles[f][k] = welder.insert(
                        {float_key(c[3 * k]), float_key(c[3 * k + 1]), float_key(c[3 * k + 2])});
                }
            }
            return std::nullopt;
        };
        detail::ExactWelder<std::uint32_t> first(3 * n);  // sized for the whole file
        if (n < kTwoBlockWeldFacets) {
            if (auto bad = weld_range(first, 0, n)) return *bad;
        } else {
            // Two halves welded at once, then the second's classes inserted into the first's
            // welder in their order: a class the first half has keeps its number, a new one
            // takes the next. The same numbering as one pass over the file (by first
            // occurrence), whatever the thread count.
            const std::uint64_t half = n / 2;
            detail::ExactWelder<std::uint32_t> second(3 * (n - half));
            std::optional<Error> bad_first, bad_second;
            tbb::parallel_invoke([&] { bad_first = weld_range(first, 0, half); },
                                 [&] { bad_second = weld_range(second, half, n); });
            if (bad_first) return *bad_first;  // the earlier byte
            if (bad_second) return *bad_second;
            std::vector<std::uint32_t> to_first;
            detail::resize_huge(to_first, second.size());
            for (std::size_t k = 0; k < second.size(); ++k)
                to_first[k] = first.insert(second.keys()[k]);
            tbb::parallel_for(tbb::blocked_range<std::uint64_t>(half, n, 1 << 15),
                              [&](const tbb::blocked_range<std::uint64_t>& range) {
                                  for (std::uint64_t f = range.begin(); f != range.end(); ++f)
                                      for (auto& v : soup.triangles[f]) v = to_first[v];
                              });
        }
        take_welded_points(first, 3 * n, soup);
        return soup;
    }
    detail::resize_huge(soup.points, 3 * n);
    Vec3* out = soup.points.data();
    for (std::uint64_t f = 0; f < n; ++f, rec += kStlRecordBytes) {
        float c[9];
        if (auto bad = load(f, rec, c)) return *bad;
        out[3 * f + 0] = {c[0], c[1], c[2]};
        out[3 * f + 1] = {c[3], c[4], c[5]};
        out[3 * f + 2] = {c[6], c[7], c[8]};
        const auto i = static_cast<std::uint32_t>(3 * f);
        soup.triangles[f] = {i, i + 1, i + 2};
    }
    return soup;
}

Result<TriangleSoup> read_ascii(std::span<const std::byte> bytes, std::string_view name) {
    io_detail::Scanner sc{reinterpret_cast<const char*>(bytes.data()),
                          reinterpret_cast<const char*>(bytes.data()) + bytes.size()};
    TriangleSoup soup;
    soup.format = InputFormat::kStlAscii;
    // The smallest facet record is far longer than this, so a reservation from the file size
    // can never exceed what the file holds.
    constexpr std::size_t kMinAsciiFacetBytes = 64;
    detail::reserve_huge(soup.triangles, bytes.size() / kMinAsciiFacetBytes);
    detail::reserve_huge(soup.points, 3 * (bytes.size() / kMinAsciiFacetBytes));

    auto expect = [&](std::string_view keyword) -> Status {
        const std::string_view tok = sc.token();
        if (tok.empty()) {
            return make_error(ErrorCode::kTruncated, name,
                              "file ends where '" + std::string(keyword) + "' was expected",
                              sc.line);
        }
        if (!iequals(tok, keyword)) {
            return make_error(ErrorCode::kBadSyntax, name,
                              "expected '" + std::string(keyword) + "', found " + quote(tok),
                              sc.line);
        }
        return Ok{};
    };
    // Coordinates are float32 in the STL format: the text is rounded to float once, so an
    // ASCII file and its binary twin give the same mesh.
    auto number = [&](float& v, bool must_be_finite) -> Status {
        const std::string_view tok = sc.token();
        if (tok.empty()) {
            return make_error(ErrorCode::kTruncated, name, "file ends where a number was expected",
                              sc.line);
        }
        if (!io_detail::parse_float(tok, v)) {
            // from_chars reports out-of-range values (1e99) as errors: say which.
            double d;
            if (io_detail::parse_double(tok, d)) {
                return make_error(ErrorCode::kBadNumber, name,
                                  "number " + quote(tok) + " is out of float32 range", sc.line);
            }
            return make_error(ErrorCode::kBadNumber, name, "expected a number, found " + quote(tok),
                              sc.line);
        }
        if (must_be_finite && !std::isfinite(v)) {
            return make_error(ErrorCode::kBadNumber, name,
                              "vertex coordinate " + quote(tok) + " is not finite", sc.line);
        }
        return Ok{};
    };

    if (auto s = expect("solid"); !s) return s.error();
    soup.name = std::string(sc.rest_of_line());
    for (;;) {
        const std::string_view tok = sc.token();
        if (tok.empty()) {
            return make_error(ErrorCode::kTruncated, name, "file ends before 'endsolid'", sc.line);
        }
        if (iequals(tok, "endsolid")) {
            (void)sc.rest_of_line();
            sc.skip_space();
            if (sc.at_end()) break;
            // Some exporters write several solids in one file: read them all.
            if (auto s = expect("solid"); !s) {
                Error e = s.error();
                e.code = ErrorCode::kTrailingContent;
                e.message = "after 'endsolid': " + e.message;
                return e;
            }
            (void)sc.rest_of_line();
            continue;
        }
        if (!iequals(tok, "facet")) {
            return make_error(ErrorCode::kBadSyntax, name,
                              "expected 'facet' or 'endsolid', found " + quote(tok), sc.line);
        }
        if (soup.triangles.size() >= kMaxFacets) {
            return make_error(ErrorCode::kTooLarge, name, "more facets than this build can address",
                              sc.line);
        }
        if (auto s = expect("normal"); !s) return s.error();
        float ignored;
        for (int k = 0; k < 3; ++k) {
            // The stored normal is ignored (vertex order defines orientation); exporters write
            // NaN for degenerate facets, so it need not be finite.
            if (auto s = number(ignored, false); !s) return s.error();
        }
        if (auto s = expect("outer"); !s) return s.error();
        if (auto s = expect("loop"); !s) return s.error();
        const auto first = static_cast<std::uint32_t>(soup.points.size());
        for (int k = 0; k < 3; ++k) {
            if (auto s = expect("vertex"); !s) return s.error();
            float p[3];
            for (int c = 0; c < 3; ++c) {
                if (auto s = number(p[c], true); !s) return s.error();
            }
            soup.points.push_back({p[0], p[1], p[2]});
        }
        if (auto s = expect("endloop"); !s) return s.error();
        if (auto s = expect("endfacet"); !s) return s.error();
        soup.triangles.push_back({first, first + 1, first + 2});
    }
    return soup;
}

bool starts_with_solid(std::span<const std::byte> bytes) {
    std::string_view s(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    if (s.substr(0, 3) == "\xEF\xBB\xBF") s.remove_prefix(3);  // UTF-8 byte order mark
    while (!s.empty() && io_detail::is_space(s.front())) s.remove_prefix(1);
    return s.size() >= 5 && iequals(s.substr(0, 5), "solid") &&
           (s.size() == 5 || io_detail::is_space(s[5]));
}

}  // namespace

Result<TriangleSoup> read_stl(std::span<const std::byte> bytes, std::string_view name,
                              const ReadOptions& options) {
    if (bytes.empty()) return make_error(ErrorCode::kEmpty, name, "file is empty");
    const std::uint64_t size = bytes.size();
    std::uint64_t n = 0;
    const bool has_header = size >= kStlHeaderBytes;
    if (has_header) n = load_u32(bytes.data() + 80);
    if (has_header && kStlHeaderBytes + kStlRecordBytes * n == size) {
        return read_binary(bytes, name, options.weld_exact);
    }

    const bool looks_ascii = starts_with_solid(bytes);
    auto binary_size_error = [&]() -> Error {
        if (!has_header) {
            return make_error(ErrorCode::kTruncated, name,
                              "not an ASCII STL, and too short for a binary STL: " +
                                  std::to_string(size) + " bytes, a binary header needs 84",
                              -1, static_cast<std::int64_t>(size));
        }
        const std::uint64_t want = kStlHeaderBytes + kStlRecordBytes * n;
        const std::uint64_t holds = (size - kStlHeaderBytes) / kStlRecordBytes;
        if (size < want) {
            return make_error(ErrorCode::kTruncated, name,
                              "truncated binary STL: header says " + std::to_string(n) +
                                  " facets, file holds " + std::to_string(holds),
                              -1, static_cast<std::int64_t>(size));
        }
        return make_error(ErrorCode::kSizeMismatch, name,
                          "binary STL size mismatch: header says " + std::to_string(n) +
                              " facets (" + std::to_string(want) + " bytes), file has " +
                              std::to_string(size) + " bytes",
                          -1, static_cast<std::int64_t>(want));
    };
    if (!looks_ascii) return binary_size_error();
    auto ascii = read_ascii(bytes, name);
    if (ascii.ok() && options.weld_exact) weld_float_points(*ascii);
    if (ascii.ok() || !has_header) return ascii;
    // A file that begins with "solid" but holds NUL bytes is a binary STL whose size is off:
    // say that rather than report an ASCII syntax error on binary data.
    const std::size_t probe = std::min<std::size_t>(bytes.size(), 4096);
    for (std::size_t i = 0; i < probe; ++i) {
        if (bytes[i] == std::byte{0}) return binary_size_error();
    }
    return ascii;
}

}  // namespace ncrev
