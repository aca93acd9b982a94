// SRE reader, version 1, exactly as ../shared/docs/sre-format.md defines it. Every error the
// page lists is reported with its 1-based line number.
#include <algorithm>
#include <numbers>

#include "io/text.h"
#include "ncrev/io.h"

namespace ncrev {

namespace {

using io_detail::parse_double;
using io_detail::parse_int;
using io_detail::quote;

// The shortest possible record ("0 0 0" plus a newline) is 6 bytes: reservations never exceed
// what the remaining bytes could hold, however large the announced count.
constexpr std::size_t kMinRecordBytes = 6;

// Keywords and parameter counts come from to_string() and num_surface_params() (writers.cpp),
// so reader and writer cannot disagree.
constexpr SurfaceKind kSurfaceKinds[] = {
    SurfaceKind::kPlane, SurfaceKind::kCylinder,      SurfaceKind::kCone,      SurfaceKind::kSphere,
    SurfaceKind::kTorus, SurfaceKind::kShearCylinder, SurfaceKind::kSweptTorus};
constexpr ToolKind kToolKinds[] = {ToolKind::kFlat, ToolKind::kBall, ToolKind::kBullnose,
                                   ToolKind::kDrill, ToolKind::kOther};

bool is_block_keyword(std::string_view s) {
    return s == "unit" || s == "tools" || s == "surfaces" || s == "vertices" || s == "facets";
}

/// Splits the input into records: non-blank lines with comments removed, as fields.
class RecordReader {
   public:
    RecordReader(const char* begin, const char* end) : p_(begin), end_(end) {}

    /// Advances to the next record; false at the end of the input.
    bool next() {
        fields_.clear();
        while (p_ < end_) {
            ++line_;
            const char* s = p_;
            while (p_ < end_ && *p_ != '\n') ++p_;
            const char* e = p_;
            if (p_ < end_) ++p_;  // the newline
            const char* hash = std::find(s, e, '#');
            line_end_ = hash;
            const char* q = s;
            while (q < hash) {
                while (q < hash && io_detail::is_space(*q)) ++q;
                const char* t = q;
                while (q < hash && !io_detail::is_space(*q)) ++q;
                if (q > t) fields_.emplace_back(t, static_cast<std::size_t>(q - t));
            }
            if (!fields_.empty()) return true;
        }
        return false;
    }
    const std::vector<std::string_view>& fields() const { return fields_; }
    std::int64_t line() const { return line_; }
    std::size_t remaining_bytes() const { return static_cast<std::size_t>(end_ - p_); }
    /// The text of the current record from field `i` to the end (comment excluded), trimmed.
    std::string_view tail_from(std::size_t i) const {
        if (i >= fields_.size()) return {};
        const char* s = fields_[i].data();
        const char* e = line_end_;
        while (e > s && io_detail::is_space(e[-1])) --e;
        return {s, static_cast<std::size_t>(e - s)};
    }

   private:
    const char* p_;
    const char* end_;
    const char* line_end_ = nullptr;
    std::int64_t line_ = 0;
    std::vector<std::string_view> fields_;
};

class SreParser {
   public:
    SreParser(std::span<const std::byte> bytes, std::string_view name)
        : in_(reinterpret_cast<const char*>(bytes.data()),
              reinterpret_cast<const char*>(bytes.data()) + bytes.size()),
          name_(name) {}

    Result<TriangleSoup> parse() {
        soup_.format = InputFormat::kSre;
        if (auto s = header(); !s) return s.error();
        bool have = in_.next();
        if (have && in_.fields()[0] == "unit") {
            if (auto s = unit(); !s) return s.error();
            have = in_.next();
        }
        if (have && in_.fields()[0] == "tools") {
            if (auto s = block("tools", &SreParser::tool_record); !s) return s.error();
            have = in_.next();
        }
        if (auto s = expect_block(have, "surfaces"); !s) return s.error();
        if (auto s = block("surfaces", &SreParser::surface_record); !s) return s.error();
        if (auto s = check_surfaces_complete(); !s) return s.error();
        have = in_.next();
        if (auto s = expect_block(have, "vertices"); !s) return s.error();
        if (auto s = block("vertices", &SreParser::vertex_record); !s) return s.error();
        have = in_.next();
        if (auto s = expect_block(have, "facets"); !s) return s.error();
        if (auto s = block("facets", &SreParser::facet_record); !s) return s.error();
        if (in_.next()) {
            if (looks_like_record_of("facets")) {
                return error(ErrorCode::kBadCount, "more facet records than the " +
                                                       std::to_string(announced_) + " announced");
            }
            return error(ErrorCode::kTrailingContent,
                         "content after the last block: " + quote(in_.fields()[0]));
        }
        return std::move(soup_);
    }

   private:
    Error error(ErrorCode code, std::string message, std::int64_t line = 0) const {
        Error e;
        e.code = code;
        e.path = std::string(name_);
        e.message = std::move(message);
        e.line = line > 0 ? line : in_.line();
        return e;
    }

    Status header() {
        if (!in_.next()) return error(ErrorCode::kBadSyntax, "missing header: expected 'SRE 1'");
        const auto& f = in_.fields();
        if (f[0] != "SRE") {
            return error(ErrorCode::kBadSyntax, "expected header 'SRE 1', found " + quote(f[0]));
        }
        if (f.size() != 2) {
            return error(ErrorCode::kBadSyntax,
                         "header takes 2 fields ('SRE 1'), found " + std::to_string(f.size()));
        }
        std::int64_t version = 0;
        if (!parse_int(f[1], version)) {
            return error(ErrorCode::kBadSyntax, "expected a version number, found " + quote(f[1]));
        }
        if (version != 1) {
            return error(ErrorCode::kBadValue, "unknown SRE version " + std::to_string(version) +
                                                   " (this reader knows version 1)");
        }
        return Ok{};
    }

    Status unit() {
        const auto& f = in_.fields();
        if (f.size() != 2) {
            return error(ErrorCode::kBadSyntax, "'unit' takes one value (mm or inch), found " +
                                                    std::to_string(f.size() - 1));
        }
        if (f[1] == "mm") {
            soup_.unit = Unit::kMillimetre;
        } else if (f[1] == "inch") {
            soup_.unit = Unit::kInch;
        } else {
            return error(ErrorCode::kBadValue,
                         "unknown unit " + quote(f[1]) + ", expected mm or inch");
        }
        return Ok{};
    }

    Status expect_block(bool have, std::string_view keyword) {
        if (!have) {
            return error(ErrorCode::kBadSyntax,
                         "file ends where block '" + std::string(keyword) + "' was expected");
        }
        const std::string_view found = in_.fields()[0];
        if (found == keyword) return Ok{};
        if (!prev_block_.empty() && looks_like_record_of(prev_block_)) {
            return error(ErrorCode::kBadCount, "block '" + std::string(prev_block_) +
                                                   "' holds more records than the " +
                                                   std::to_string(announced_) + " announced");
        }
        if (is_block_keyword(found)) {
            return error(ErrorCode::kBadSyntax, "block " + quote(found) +
                                                    " out of order or block '" +
                                                    std::string(keyword) + "' missing: expected '" +
                                                    std::string(keyword) + "'");
        }
        return error(ErrorCode::kBadSyntax,
                     "expected block '" + std::string(keyword) + "', found " + quote(found));
    }

    bool looks_like_record_of(std::string_view keyword) const {
        const std::string_view f0 = in_.fields()[0];
        if (keyword == "tools") return f0 == "tool";
        double d;
        return parse_double(f0, d);
    }

    using RecordFn = Status (SreParser::*)();

    Status block(std::string_view keyword, RecordFn record) {
        const auto& f = in_.fields();
        const std::int64_t header_line = in_.line();
        if (f.size() != 2) {
            return error(ErrorCode::kBadSyntax, "block '" + std::string(keyword) +
                                                    "' takes one count, found " +
                                                    std::to_string(f.size() - 1) + " fields");
        }
        std::int64_t count = -1;
        if (!parse_int(f[1], count) || count < 0) {
            return error(ErrorCode::kBadCount,
                         "count must be a non-negative integer, found " + quote(f[1]));
        }
        if (static_cast<std::uint64_t>(count) >= 0xFFFFFFFFull) {
            return error(ErrorCode::kTooLarge,
                         "count " + std::to_string(count) + " exceeds what 32-bit ids can address");
        }
        announced_ = count;
        header_line_ = header_line;
        prev_block_ = keyword;
        const std::size_t plausible = std::min<std::size_t>(
            static_cast<std::size_t>(count), in_.remaining_bytes() / kMinRecordBytes + 1);
        reserve(keyword, plausible, static_cast<std::size_t>(count));
        for (std::int64_t i = 0; i < count; ++i) {
            if (!in_.next()) {
                return error(ErrorCode::kBadCount,
                             "file ends after " + std::to_string(i) + " of the " +
                                 std::to_string(count) + " records block '" + std::string(keyword) +
                                 "' announced (line " + std::to_string(header_line) + ")");
            }
            if (is_block_keyword(in_.fields()[0])) {
                return error(ErrorCode::kBadCount,
                             "block '" + std::string(keyword) + "' announced " +
                                 std::to_string(count) + " records (line " +
                                 std::to_string(header_line) + ") but holds " + std::to_string(i));
            }
            if (auto s = (this->*record)(); !s) return s;
        }
        return Ok{};
    }

    void reserve(std::string_view keyword, std::size_t plausible, std::size_t count) {
        if (keyword == "tools") {
            soup_.tools.reserve(plausible);
        } else if (keyword == "surfaces") {
            // Surfaces are addressed by index, so the table needs `count` slots; it is only
            // allocated up to what the file could hold, and grows as records arrive.
            surface_seen_line_.assign(std::min(count, plausible), 0);
            soup_.surfaces.resize(surface_seen_line_.size());
            surface_count_ = count;
        } else if (keyword == "vertices") {
            soup_.points.reserve(plausible);
        } else {
            soup_.triangles.reserve(plausible);
            soup_.color.reserve(plausible);
            soup_.cut.reserve(plausible);
            soup_.surface.reserve(plausible);
        }
    }

    Status number(std::string_view tok, double& v) {
        if (!parse_double(tok, v)) {
            return error(ErrorCode::kBadNumber, "expected a number, found " + quote(tok));
        }
        if (!std::isfinite(v)) return error(ErrorCode::kBadNumber, quote(tok) + " is not finite");
        return Ok{};
    }
    Status integer(std::string_view tok, std::int64_t& v) {
        if (!parse_int(tok, v)) {
            return error(ErrorCode::kBadNumber, "expected an integer, found " + quote(tok));
        }
        return Ok{};
    }
    Status field_count(std::size_t want, std::string_view what) {
        const std::size_t have = in_.fields().size();
        if (have == want) return Ok{};
        return error(ErrorCode::kBadSyntax, std::string(what) + " takes " + std::to_string(want) +
                                                " fields, found " + std::to_string(have));
    }

    Status tool_record() {
        const auto& f = in_.fields();
        if (f[0] != "tool")
            return error(ErrorCode::kBadSyntax, "expected 'tool', found " + quote(f[0]));
        if (f.size() < 5) {
            return error(ErrorCode::kBadSyntax,
                         "a tool record takes at least 5 fields (tool color kind diameter "
                         "corner_radius [name]), found " +
                             std::to_string(f.size()));
        }
        ToolRecord t;
        if (auto s = integer(f[1], t.color); !s) return s;
        bool known = false;
        for (ToolKind k : kToolKinds) {
            if (f[2] == to_string(k)) {
                t.kind = k;
                known = true;
            }
        }
        if (!known) {
            return error(ErrorCode::kBadValue,
                         "unknown tool kind " + quote(f[2]) +
                             ", expected flat, ball, bullnose, drill or other");
        }
        if (auto s = number(f[3], t.diameter); !s) return s;
        if (auto s = number(f[4], t.corner_radius); !s) return s;
        if (t.diameter <= 0) return error(ErrorCode::kBadValue, "tool diameter must be positive");
        if (t.corner_radius < 0 || t.corner_radius > t.diameter / 2) {
            return error(ErrorCode::kBadValue,
                         "tool corner radius must lie between 0 and half the diameter");
        }
        t.name = std::string(in_.tail_from(5));
        soup_.tools.push_back(std::move(t));
        return Ok{};
    }

    static bool is_zero(const double* v) { return v[0] == 0 && v[1] == 0 && v[2] == 0; }

    Status surface_record() {
        const auto& f = in_.fields();
        if (f.size() < 2) {
            return error(ErrorCode::kBadSyntax,
                         "a surface record takes an index, a kind and its "
                         "parameters, found 1 field");
        }
        std::int64_t index = 0;
        if (auto s = integer(f[0], index); !s) return s;
        const SurfaceKind* kind = nullptr;
        for (const SurfaceKind& k : kSurfaceKinds) {
            if (f[1] == to_string(k)) kind = &k;
        }
        if (kind == nullptr) {
            return error(ErrorCode::kBadValue,
                         "unknown surface kind " + quote(f[1]) +
                             ", expected plane, cylinder, cone, sphere, torus, shear_cylinder or "
                             "swept_torus");
        }
        const int num_params = num_surface_params(*kind);
        if (f.size() != static_cast<std::size_t>(2 + num_params)) {
            return error(ErrorCode::kBadSyntax,
                         std::string(to_string(*kind)) + " takes " + std::to_string(num_params) +
                             " parameters, found " + std::to_string(f.size() - 2));
        }
        SurfaceRecord r;
        r.kind = *kind;
        for (int i = 0; i < num_params; ++i) {
            if (auto s = number(f[2 + i], r.params[i]); !s) return s;
        }
        if (auto s = validate_surface(r); !s) return s;
        if (index < 0 || static_cast<std::uint64_t>(index) >= surface_count_) {
            return error(ErrorCode::kIndexOutOfRange,
                         "surface index " + std::to_string(index) + " out of range 0.." +
                             std::to_string(static_cast<std::int64_t>(surface_count_) - 1));
        }
        const auto idx = static_cast<std::size_t>(index);
        if (idx >= surface_seen_line_.size()) {
            surface_seen_line_.resize(idx + 1, 0);
            soup_.surfaces.resize(idx + 1);
        }
        if (surface_seen_line_[idx] != 0) {
            return error(ErrorCode::kDuplicateIndex,
                         "surface index " + std::to_string(index) + " given twice (first on line " +
                             std::to_string(surface_seen_line_[idx]) + ")");
        }
        surface_seen_line_[idx] = in_.line();
        soup_.surfaces[idx] = r;
        return Ok{};
    }

    Status validate_surface(const SurfaceRecord& r) {
        const double* p = r.params.data();
        auto bad = [&](const std::string& what) {
            return error(ErrorCode::kBadValue, std::string(to_string(r.kind)) + ": " + what);
        };
        switch (r.kind) {
            case SurfaceKind::kPlane:
                if (is_zero(p + 3)) return bad("zero normal vector");
                break;
            case SurfaceKind::kCylinder:
                if (is_zero(p + 3)) return bad("zero axis direction");
                if (!(p[6] > 0)) return bad("radius must be positive");
                break;
            case SurfaceKind::kCone:
                if (is_zero(p + 3)) return bad("zero axis direction");
                if (p[6] < 0) return bad("radius must not be negative");
                if (!(p[7] > 0 && p[7] < std::numbers::pi / 2)) {
                    return bad("half-angle must lie strictly between 0 and pi/2");
                }
                break;
            case SurfaceKind::kSphere:
                if (!(p[3] > 0)) return bad("radius must be positive");
                break;
            case SurfaceKind::kTorus:
            case SurfaceKind::kSweptTorus:
                if (is_zero(p + 3)) return bad("zero axis direction");
                if (!(p[6] > 0)) return bad("major radius R must be positive");
                if (!(p[7] > 0)) return bad("minor radius r must be positive");
                if (r.kind == SurfaceKind::kSweptTorus && is_zero(p + 8)) {
                    return bad("zero sweep direction");
                }
                break;
            case SurfaceKind::kShearCylinder: {
                if (is_zero(p + 3)) return bad("zero axis direction");
                if (!(p[6] > 0)) return bad("radius must be positive");
                if (is_zero(p + 7)) return bad("zero sweep direction");
                const Vec3 a{p[3], p[4], p[5]}, d{p[7], p[8], p[9]};
                // d must leave the plane of the circle; compared relative to the lengths so
                // that the test does not depend on how the vectors are scaled.
                constexpr double kParallelRelative = 1e-12;
                if (std::abs(dot(a, d)) <= kParallelRelative * norm(a) * norm(d)) {
                    return bad("sweep direction lies in the plane of the circle");
                }
                break;
            }
        }
        return Ok{};
    }

    Status check_surfaces_complete() {
        if (surface_seen_line_.size() < surface_count_) {
            return error(ErrorCode::kMissingIndex,
                         "surface index " + std::to_string(surface_seen_line_.size()) +
                             " is missing (block announced " + std::to_string(surface_count_) + ")",
                         header_line_);
        }
        for (std::size_t i = 0; i < surface_seen_line_.size(); ++i) {
            if (surface_seen_line_[i] == 0) {
                return error(ErrorCode::kMissingIndex,
                             "surface index " + std::to_string(i) +
                                 " is missing (block announced " + std::to_string(surface_count_) +
                                 ")",
                             header_line_);
            }
        }
        surface_seen_line_ = {};
        return Ok{};
    }

    Status vertex_record() {
        if (auto s = field_count(3, "a vertex record"); !s) return s;
        const auto& f = in_.fields();
        Vec3 v;
        for (int i = 0; i < 3; ++i) {
            if (auto s = number(f[i], v[i]); !s) return s;
        }
        soup_.points.push_back(v);
        return Ok{};
    }

    Status facet_record() {
        if (auto s = field_count(6, "a facet record (v0 v1 v2 color cut surface)"); !s) return s;
        const auto& f = in_.fields();
        std::int64_t v[3], color = 0, cut = 0, surface = 0;
        for (int i = 0; i < 3; ++i) {
            if (auto s = integer(f[i], v[i]); !s) return s;
        }
        if (auto s = integer(f[3], color); !s) return s;
        if (auto s = integer(f[4], cut); !s) return s;
        if (auto s = integer(f[5], surface); !s) return s;
        const auto num_vertices = static_cast<std::int64_t>(soup_.points.size());
        for (int i = 0; i < 3; ++i) {
            if (v[i] < 0 || v[i] >= num_vertices) {
                return error(ErrorCode::kIndexOutOfRange, "vertex index " + std::to_string(v[i]) +
                                                              " out of range 0.." +
                                                              std::to_string(num_vertices - 1));
            }
        }
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
            return error(ErrorCode::kBadValue, "facet repeats a vertex");
        }
        if (cut < -1) {
            return error(ErrorCode::kBadValue,
                         "cut must be a non-negative integer or -1, found " + std::to_string(cut));
        }
        const auto num_surfaces = static_cast<std::int64_t>(soup_.surfaces.size());
        if (surface < -1 || surface >= num_surfaces) {
            return error(ErrorCode::kIndexOutOfRange, "surface index " + std::to_string(surface) +
                                                          " out of range (-1 or 0.." +
                                                          std::to_string(num_surfaces - 1) + ")");
        }
        soup_.triangles.push_back({static_cast<std::uint32_t>(v[0]),
                                   static_cast<std::uint32_t>(v[1]),
                                   static_cast<std::uint32_t>(v[2])});
        soup_.color.push_back(color);
        soup_.cut.push_back(cut);
        soup_.surface.push_back(static_cast<std::int32_t>(surface));
        return Ok{};
    }

    RecordReader in_;
    std::string_view name_;
    TriangleSoup soup_;
    std::int64_t announced_ = 0;
    std::string_view prev_block_;
    std::int64_t header_line_ = 0;
    std::uint64_t surface_count_ = 0;
    std::vector<std::int64_t> surface_seen_line_;
};

}  // namespace

Result<TriangleSoup> read_sre(std::span<const std::byte> bytes, std::string_view name) {
    if (bytes.empty()) {
        Error e;
        e.code = ErrorCode::kEmpty;
        e.path = std::string(name);
        e.message = "file is empty";
        return e;
    }
    return SreParser(bytes, name).parse();
}

namespace {

bool begins_with_sre_header(std::span<const std::byte> bytes) {
    RecordReader r(
        reinterpret_cast<const char*>(bytes.data()),
        reinterpret_cast<const char*>(bytes.data()) + std::min<std::size_t>(bytes.size(), 4096));
    return r.next() && r.fields()[0] == "SRE";
}

}  // namespace

Result<TriangleSoup> read_mesh(std::span<const std::byte> bytes, std::string_view name,
                               const ReadOptions& options) {
    if (begins_with_sre_header(bytes)) return read_sre(bytes, name);
    return read_stl(bytes, name, options);
}

Result<TriangleSoup> read_mesh_file(const std::filesystem::path& path, const ReadOptions& options) {
    auto file = FileBytes::open(path);
    if (!file) return file.error();
    const std::string name = path.string();
    std::string ext = path.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext == ".sre") return read_sre(file->bytes(), name);
    return read_mesh(file->bytes(), name, options);
}

}  // namespace ncrev
