// io: reading and writing the meshes engineers have — STL (ASCII and binary), SRE (the NC
// simulator's attributed mesh, docs/formats: ../shared/docs/sre-format.md) — and PLY for viewers.
//
// Trust boundary: every reader takes a byte span it does not trust. Every bound is checked in
// every build type; nothing is allocated on the strength of a count the file merely claims; a
// malformed file gives an Error with its code, the 1-based line (text) or 0-based byte offset
// (binary), and what was expected. Readers never throw, never print.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ncrev/common.h"

namespace ncrev {

enum class InputFormat { kStlBinary, kStlAscii, kSre };
/// "stl-binary", "stl-ascii", "sre".
const char* to_string(InputFormat format);

/// Length unit of a model. STL has none: readers assume millimetres and say so.
enum class Unit { kMillimetre, kInch };
/// "mm", "inch".
const char* to_string(Unit unit);

/// Surface kinds an SRE file (and later, fitting) names.
enum class SurfaceKind { kPlane, kCylinder, kCone, kSphere, kTorus, kShearCylinder, kSweptTorus };
/// The SRE keyword: "plane", "cylinder", "cone", "sphere", "torus", "shear_cylinder",
/// "swept_torus".
const char* to_string(SurfaceKind kind);
/// Number of parameters the SRE format gives a kind (plane 6 ... swept_torus 11).
int num_surface_params(SurfaceKind kind);

/// One analytic surface as the SRE format states it: `params` in the order of the format's
/// table (e.g. cylinder: px py pz ax ay az r), unused trailing entries zero. Lengths in the
/// file's unit, angles in radians; directions as given (not normalised).
struct SurfaceRecord {
    SurfaceKind kind = SurfaceKind::kPlane;
    std::array<double, 11> params{};
};

enum class ToolKind { kFlat, kBall, kBullnose, kDrill, kOther };
/// "flat", "ball", "bullnose", "drill", "other".
const char* to_string(ToolKind kind);

/// One cutting tool of an SRE file.
struct ToolRecord {
    std::int64_t color = 0;  ///< the color its facets carry (e.g. 0xRRGGBB)
    ToolKind kind = ToolKind::kOther;
    double diameter = 0;       ///< file unit, > 0
    double corner_radius = 0;  ///< file unit, 0 <= corner_radius <= diameter / 2
    std::string name;          ///< free text, may be empty
};

/// What a reader returns: triangles over a point list, plus what the format carried.
/// STL gives three fresh points per facet (a "bucket of facets"); SRE gives shared vertices.
/// Per-facet attribute vectors are either empty (the format has none) or one entry per facet.
struct TriangleSoup {
    InputFormat format = InputFormat::kStlBinary;
    Unit unit = Unit::kMillimetre;
    std::string name;  ///< STL solid name / header text; empty for SRE

    std::vector<Vec3> points;
    std::vector<std::array<std::uint32_t, 3>> triangles;  ///< indices into points

    std::vector<std::int64_t> color;    ///< SRE: tool color, 0 if unknown
    std::vector<std::int64_t> cut;      ///< SRE: tool movement, -1 if unknown
    std::vector<std::int32_t> surface;  ///< SRE: index into `surfaces`, -1 if unknown

    std::vector<ToolRecord> tools;        ///< SRE tools block (may be empty)
    std::vector<SurfaceRecord> surfaces;  ///< SRE surfaces, indexed by surface index

    /// True when no two points are bit-identical (the reader welded exactly, see
    /// ReadOptions::weld_exact); build_mesh() then skips its own exact weld.
    bool points_distinct = false;
    /// Points the reader merged into an earlier identical one: the file held
    /// points.size() + welded_points points.
    std::uint64_t welded_points = 0;

    std::size_t num_facets() const { return triangles.size(); }
    bool has_attributes() const { return !surface.empty(); }
};

/// How to read.
struct ReadOptions {
    /// STL: merge bit-identical points while reading (an exact weld), so the soup holds each
    /// vertex once and the triangles share them. Same mesh as welding later, at a third of
    /// the memory and much less time; build_mesh() counts the merges in its report.
    bool weld_exact = false;
};

/// Reads a binary or ASCII STL. Binary is recognised by its size (84 + 50·n bytes, n the
/// header's count), not by a leading "solid": many binary files begin with that word. Facet
/// normals are ignored (the vertex order defines orientation). NaN or infinite coordinates
/// are errors. `name` is only used in error messages.
Result<TriangleSoup> read_stl(std::span<const std::byte> bytes, std::string_view name = {},
                              const ReadOptions& options = {});

/// Reads an SRE file exactly as ../shared/docs/sre-format.md (version 1) defines it; every
/// error that page lists is reported with its line.
Result<TriangleSoup> read_sre(std::span<const std::byte> bytes, std::string_view name = {});

/// Recognises the format (SRE by its header, else STL) and reads it.
Result<TriangleSoup> read_mesh(std::span<const std::byte> bytes, std::string_view name = {},
                               const ReadOptions& options = {});

/// Reads a file: SRE if its extension is .sre or it begins with the SRE header, else STL.
/// Error paths name the file.
Result<TriangleSoup> read_mesh_file(const std::filesystem::path& path,
                                    const ReadOptions& options = {});

/// The bytes of a file, memory-mapped (read-only) when possible. Movable, not copyable.
class FileBytes {
   public:
    static Result<FileBytes> open(const std::filesystem::path& path);
    FileBytes() = default;
    FileBytes(FileBytes&& other) noexcept;
    FileBytes& operator=(FileBytes&& other) noexcept;
    FileBytes(const FileBytes&) = delete;
    FileBytes& operator=(const FileBytes&) = delete;
    ~FileBytes();

    std::span<const std::byte> bytes() const { return {data_, size_}; }

   private:
    const std::byte* data_ = nullptr;
    std::size_t size_ = 0;
    bool mapped_ = false;
    std::vector<std::byte> owned_;  // fallback when mmap is not possible (e.g. a pipe)
};

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, flushed, then
/// renamed over `path`. On failure nothing is left behind and `path` is untouched.
Status write_file_atomic(const std::filesystem::path& path, std::span<const std::byte> bytes);

/// Writes a file in pieces, atomically: a temporary file beside the target, renamed over it
/// by commit(). Destroyed (or after a failed write) without commit(), it removes the
/// temporary file and leaves the target untouched. Movable, not copyable.
class AtomicFileWriter {
   public:
    static Result<AtomicFileWriter> open(const std::filesystem::path& path);
    AtomicFileWriter() = default;
    AtomicFileWriter(AtomicFileWriter&& other) noexcept;
    AtomicFileWriter& operator=(AtomicFileWriter&& other) noexcept;
    AtomicFileWriter(const AtomicFileWriter&) = delete;
    AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
    ~AtomicFileWriter();

    Status write(std::span<const std::byte> bytes);
    /// Flushes to disk and renames the temporary file over the target.
    Status commit();

   private:
    void abandon();
    std::filesystem::path path_, tmp_;
    int fd_ = -1;
};

/// Encodes a binary STL (80-byte header from `header`, normals computed from the vertices,
/// coordinates rounded to float32).
std::vector<std::byte> encode_stl_binary(std::span<const Vec3> points,
                                         std::span<const std::array<std::uint32_t, 3>> triangles,
                                         std::string_view header = "ncrev");

/// Encodes an ASCII STL with `solid name`; coordinates printed to round-trip float32.
std::string encode_stl_ascii(std::span<const Vec3> points,
                             std::span<const std::array<std::uint32_t, 3>> triangles,
                             std::string_view name = "ncrev");

/// Encodes an SRE version 1 file from a soup with attributes (missing attributes are written
/// as color 0, cut -1, surface -1). Numbers are written to round-trip doubles.
std::string encode_sre(const TriangleSoup& soup);

/// A named column of a PLY element.
struct PlyColumn {
    enum class Type { kFloat32, kInt32, kUint8 };
    std::string name;
    Type type = Type::kFloat32;
    std::vector<double> values;  ///< one per element, converted to `type` when written
};

/// Encodes a binary little-endian PLY: vertices (x y z as float plus `vertex_columns`) and
/// faces (`vertex_indices` plus `face_columns`, e.g. `region` int and `red green blue` uchar,
/// which MeshLab shows as face colors). Every column must have one value per element.
std::vector<std::byte> encode_ply(std::span<const Vec3> points,
                                  std::span<const std::array<std::uint32_t, 3>> triangles,
                                  std::span<const PlyColumn> vertex_columns = {},
                                  std::span<const PlyColumn> face_columns = {});

/// A well-spread, deterministic color for label `i` (0xRRGGBB), for region / type coloring.
std::uint32_t label_color(std::uint32_t i);

}  // namespace ncrev
