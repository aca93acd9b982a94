// Writers: binary and ASCII STL, SRE version 1, binary PLY with per-face labels and colors.
#include <charconv>
#include <cstring>

#include "ncrev/io.h"

namespace ncrev {

const char* to_string(InputFormat format) {
    switch (format) {
        case InputFormat::kStlBinary:
            return "stl-binary";
        case InputFormat::kStlAscii:
            return "stl-ascii";
        case InputFormat::kSre:
            return "sre";
    }
    return "unknown";
}

const char* to_string(Unit unit) { return unit == Unit::kInch ? "inch" : "mm"; }

const char* to_string(SurfaceKind kind) {
    switch (kind) {
        case SurfaceKind::kPlane:
            return "plane";
        case SurfaceKind::kCylinder:
            return "cylinder";
        case SurfaceKind::kCone:
            return "cone";
        case SurfaceKind::kSphere:
            return "sphere";
        case SurfaceKind::kTorus:
            return "torus";
        case SurfaceKind::kShearCylinder:
            return "shear_cylinder";
        case SurfaceKind::kSweptTorus:
            return "swept_torus";
    }
    return "unknown";
}

int num_surface_params(SurfaceKind kind) {
    switch (kind) {
        case SurfaceKind::kPlane:
            return 6;
        case SurfaceKind::kCylinder:
            return 7;
        case SurfaceKind::kCone:
            return 8;
        case SurfaceKind::kSphere:
            return 4;
        case SurfaceKind::kTorus:
            return 8;
        case SurfaceKind::kShearCylinder:
            return 10;
        case SurfaceKind::kSweptTorus:
            return 11;
    }
    return 0;
}

const char* to_string(ToolKind kind) {
    switch (kind) {
        case ToolKind::kFlat:
            return "flat";
        case ToolKind::kBall:
            return "ball";
        case ToolKind::kBullnose:
            return "bullnose";
        case ToolKind::kDrill:
            return "drill";
        case ToolKind::kOther:
            return "other";
    }
    return "other";
}

namespace {

template <class T>
void put(std::vector<std::byte>& out, T v) {
    const std::size_t at = out.size();
    out.resize(at + sizeof(T));
    std::memcpy(out.data() + at, &v, sizeof(T));
}

void put_text(std::vector<std::byte>& out, std::string_view s) {
    const std::size_t at = out.size();
    out.resize(at + s.size());
    std::memcpy(out.data() + at, s.data(), s.size());
}

/// Shortest text that reads back as the same value.
template <class T>
void append_number(std::string& out, T v) {
    char buf[64];
    auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
    (void)ec;  // 64 chars always suffice for a double or an integer
    out.append(buf, ptr);
}

}  // namespace

std::vector<std::byte> encode_stl_binary(std::span<const Vec3> points,
                                         std::span<const std::array<std::uint32_t, 3>> triangles,
                                         std::string_view header) {
    std::vector<std::byte> out;
    out.reserve(84 + 50 * triangles.size());
    char h[80] = {};
    std::memcpy(h, header.data(), std::min<std::size_t>(header.size(), 80));
    // A binary header must not begin with "solid": some readers then take it for ASCII.
    if (header.substr(0, 5) == "solid") h[0] = 'S';
    put_text(out, std::string_view(h, 80));
    put(out, static_cast<std::uint32_t>(triangles.size()));
    for (const auto& t : triangles) {
        const Vec3 a = points[t[0]], b = points[t[1]], c = points[t[2]];
        const Vec3 n = normalized(cross(b - a, c - a));
        for (const Vec3& v : {n, a, b, c}) {
            put(out, static_cast<float>(v.x));
            put(out, static_cast<float>(v.y));
            put(out, static_cast<float>(v.z));
        }
        put(out, std::uint16_t{0});
    }
    return out;
}

std::string encode_stl_ascii(std::span<const Vec3> points,
                             std::span<const std::array<std::uint32_t, 3>> triangles,
                             std::string_view name) {
    std::string out = "solid " + std::string(name) + "\n";
    auto vec = [&](Vec3 v) {
        for (int i = 0; i < 3; ++i) {
            out += ' ';
            append_number(out, static_cast<float>(v[i]));
        }
        out += '\n';
    };
    for (const auto& t : triangles) {
        const Vec3 a = points[t[0]], b = points[t[1]], c = points[t[2]];
        out += "  facet normal";
        vec(normalized(cross(b - a, c - a)));
        out += "    outer loop\n";
        for (const Vec3& v : {a, b, c}) {
            out += "      vertex";
            vec(v);
        }
        out += "    endloop\n  endfacet\n";
    }
    out += "endsolid " + std::string(name) + "\n";
    return out;
}

std::string encode_sre(const TriangleSoup& soup) {
    std::string out = "SRE 1\nunit ";
    out += to_string(soup.unit);
    out += '\n';
    if (!soup.tools.empty()) {
        out += "tools " + std::to_string(soup.tools.size()) + "\n";
        for (const ToolRecord& t : soup.tools) {
            out += "tool ";
            append_number(out, t.color);
            out += ' ';
            out += to_string(t.kind);
            out += ' ';
            append_number(out, t.diameter);
            out += ' ';
            append_number(out, t.corner_radius);
            if (!t.name.empty()) {
                out += ' ';
                for (char c : t.name) out += (c == '\n' || c == '#') ? ' ' : c;
            }
            out += '\n';
        }
    }
    out += "surfaces " + std::to_string(soup.surfaces.size()) + "\n";
    for (std::size_t i = 0; i < soup.surfaces.size(); ++i) {
        const SurfaceRecord& s = soup.surfaces[i];
        append_number(out, i);
        out += ' ';
        out += to_string(s.kind);
        for (int k = 0; k < num_surface_params(s.kind); ++k) {
            out += ' ';
            append_number(out, s.params[k]);
        }
        out += '\n';
    }
    out += "vertices " + std::to_string(soup.points.size()) + "\n";
    for (const Vec3& p : soup.points) {
        append_number(out, p.x);
        out += ' ';
        append_number(out, p.y);
        out += ' ';
        append_number(out, p.z);
        out += '\n';
    }
    out += "facets " + std::to_string(soup.triangles.size()) + "\n";
    const bool attrs = soup.color.size() == soup.triangles.size() &&
                       soup.cut.size() == soup.triangles.size() &&
                       soup.surface.size() == soup.triangles.size();
    for (std::size_t f = 0; f < soup.triangles.size(); ++f) {
        for (int k = 0; k < 3; ++k) {
            append_number(out, soup.triangles[f][k]);
            out += ' ';
        }
        append_number(out, attrs ? soup.color[f] : std::int64_t{0});
        out += ' ';
        append_number(out, attrs ? soup.cut[f] : std::int64_t{-1});
        out += ' ';
        append_number(out, attrs ? soup.surface[f] : std::int32_t{-1});
        out += '\n';
    }
    return out;
}

std::vector<std::byte> encode_ply(std::span<const Vec3> points,
                                  std::span<const std::array<std::uint32_t, 3>> triangles,
                                  std::span<const PlyColumn> vertex_columns,
                                  std::span<const PlyColumn> face_columns) {
    auto type_name = [](PlyColumn::Type t) {
        switch (t) {
            case PlyColumn::Type::kFloat32:
                return "float";
            case PlyColumn::Type::kInt32:
                return "int";
            case PlyColumn::Type::kUint8:
                return "uchar";
        }
        return "float";
    };
    std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by ncrev\n";
    header += "element vertex " + std::to_string(points.size()) + "\n";
    header += "property float x\nproperty float y\nproperty float z\n";
    for (const PlyColumn& c : vertex_columns) {
        header += std::string("property ") + type_name(c.type) + " " + c.name + "\n";
    }
    header += "element face " + std::to_string(triangles.size()) + "\n";
    header += "property list uchar int vertex_indices\n";
    for (const PlyColumn& c : face_columns) {
        header += std::string("property ") + type_name(c.type) + " " + c.name + "\n";
    }
    header += "end_header\n";

    std::vector<std::byte> out;
    out.reserve(header.size() + points.size() * (12 + 4 * vertex_columns.size()) +
                triangles.size() * (13 + 4 * face_columns.size()));
    put_text(out, header);
    auto put_value = [&](const PlyColumn& c, std::size_t i) {
        const double v = i < c.values.size() ? c.values[i] : 0.0;
        switch (c.type) {
            case PlyColumn::Type::kFloat32:
                put(out, static_cast<float>(v));
                break;
            case PlyColumn::Type::kInt32:
                put(out, static_cast<std::int32_t>(v));
                break;
            case PlyColumn::Type::kUint8:
                put(out, static_cast<std::uint8_t>(v));
                break;
        }
    };
    for (std::size_t i = 0; i < points.size(); ++i) {
        put(out, static_cast<float>(points[i].x));
        put(out, static_cast<float>(points[i].y));
        put(out, static_cast<float>(points[i].z));
        for (const PlyColumn& c : vertex_columns) put_value(c, i);
    }
    for (std::size_t f = 0; f < triangles.size(); ++f) {
        put(out, std::uint8_t{3});
        for (int k = 0; k < 3; ++k) put(out, static_cast<std::int32_t>(triangles[f][k]));
        for (const PlyColumn& c : face_columns) put_value(c, f);
    }
    return out;
}

std::uint32_t label_color(std::uint32_t i) {
    // Golden-ratio steps around the hue circle give neighbouring labels distant hues; the
    // saturation and value cycle slowly so that labels far apart differ too.
    constexpr double kGoldenRatioConjugate = 0.618033988749895;
    const double h = std::fmod(0.13 + i * kGoldenRatioConjugate, 1.0) * 6.0;
    const double s = 0.55 + 0.35 * ((i / 7) % 2);
    const double v = 0.95 - 0.25 * ((i / 3) % 2);
    const int sector = static_cast<int>(h);
    const double frac = h - sector;
    const double p = v * (1 - s), q = v * (1 - s * frac), t = v * (1 - s * (1 - frac));
    double r = v, g = t, b = p;
    switch (sector % 6) {
        case 0:
            r = v;
            g = t;
            b = p;
            break;
        case 1:
            r = q;
            g = v;
            b = p;
            break;
        case 2:
            r = p;
            g = v;
            b = t;
            break;
        case 3:
            r = p;
            g = q;
            b = v;
            break;
        case 4:
            r = t;
            g = p;
            b = v;
            break;
        default:
            r = v;
            g = p;
            b = q;
            break;
    }
    auto byte = [](double x) { return static_cast<std::uint32_t>(std::lround(x * 255.0)); };
    return (byte(r) << 16) | (byte(g) << 8) | byte(b);
}

}  // namespace ncrev
