// Small value types shared by every module: vectors, strong 32-bit ids, and the Result type
// that carries a typed error across the library's API (no exceptions cross it).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>

namespace ncrev {

/// A 3-vector of doubles. Lengths are in the model's unit (mm unless the input says otherwise).
struct Vec3 {
    double x = 0, y = 0, z = 0;

    constexpr double& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    constexpr double operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
    friend constexpr Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
    friend constexpr Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
    friend constexpr Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
    friend constexpr Vec3 operator*(double s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
    friend constexpr Vec3 operator*(Vec3 a, double s) { return s * a; }
    friend constexpr Vec3 operator/(Vec3 a, double s) { return {a.x / s, a.y / s, a.z / s}; }
    constexpr Vec3& operator+=(Vec3 b) { return *this = *this + b; }
    constexpr Vec3& operator-=(Vec3 b) { return *this = *this - b; }
    friend constexpr bool operator==(Vec3 a, Vec3 b) = default;
};

constexpr double dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
constexpr Vec3 cross(Vec3 a, Vec3 b) {
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(Vec3 a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalized(Vec3 a) {
    const double n = norm(a);
    return n > 0 ? a / n : Vec3{};
}

/// An axis-aligned box. Empty (min > max) until a point is added.
struct Box3 {
    Vec3 min{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
             std::numeric_limits<double>::infinity()};
    Vec3 max{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
             -std::numeric_limits<double>::infinity()};

    bool empty() const { return min.x > max.x; }
    void add(Vec3 p) {
        for (int i = 0; i < 3; ++i) {
            min[i] = std::fmin(min[i], p[i]);
            max[i] = std::fmax(max[i], p[i]);
        }
    }
    void add(const Box3& b) {
        if (b.empty()) return;
        add(b.min);
        add(b.max);
    }
    /// Length of the diagonal; 0 for an empty box.
    double diagonal() const { return empty() ? 0.0 : norm(max - min); }
};

/// A strong 32-bit index: the compiler keeps a face id from being used as a vertex id.
template <class Tag>
class Id {
   public:
    using value_type = std::uint32_t;
    static constexpr value_type kInvalid = std::numeric_limits<value_type>::max();

    constexpr Id() = default;
    constexpr explicit Id(value_type v) : v_(v) {}
    constexpr value_type idx() const { return v_; }
    constexpr bool is_valid() const { return v_ != kInvalid; }
    friend constexpr auto operator<=>(Id, Id) = default;

   private:
    value_type v_ = kInvalid;
};

struct VertexTag {};
struct HalfedgeTag {};
struct FaceTag {};
struct RegionTag {};
using VertexId = Id<VertexTag>;
using HalfedgeId = Id<HalfedgeTag>;
using FaceId = Id<FaceTag>;
using RegionId = Id<RegionTag>;

/// What went wrong with an input or an output. The numeric value is stable (it names fixtures).
enum class ErrorCode {
    kCannotOpen,       ///< the file does not exist or cannot be read
    kCannotWrite,      ///< the output cannot be written
    kEmpty,            ///< zero bytes, or no facet at all
    kUnknownFormat,    ///< not STL, not SRE
    kTruncated,        ///< the file ends before what it announces
    kSizeMismatch,     ///< binary STL: facet count disagrees with the file size
    kBadNumber,        ///< a number that does not parse, or NaN / infinity
    kBadSyntax,        ///< a keyword, field count or record out of place
    kBadCount,         ///< a count that is not a non-negative integer, or records != count
    kBadValue,         ///< a value out of its domain (zero direction, radius <= 0, ...)
    kIndexOutOfRange,  ///< a vertex or surface index that names nothing
    kDuplicateIndex,   ///< an SRE surface index given twice
    kMissingIndex,     ///< an SRE surface index never given
    kTrailingContent,  ///< content after the last block
    kTooLarge,         ///< more elements than 32-bit ids can address
};

/// Short stable name of an error code (used in messages and JSON).
const char* to_string(ErrorCode code);

/// A typed error: the code, one sentence, and where (file, 1-based line or 0-based byte offset;
/// -1 where it does not apply).
struct Error {
    ErrorCode code = ErrorCode::kBadSyntax;
    std::string message;
    std::string path;
    std::int64_t line = -1;
    std::int64_t byte_offset = -1;

    /// "part.stl: line 12: expected 'vertex', found 'vertx'": the one-line text the CLI prints.
    std::string describe() const;
};

/// A value or an Error. The library returns this for every input it does not control.
template <class T>
class [[nodiscard]] Result {
   public:
    Result(T value) : v_(std::in_place_index<0>, std::move(value)) {}      // NOLINT: implicit
    Result(Error error) : v_(std::in_place_index<1>, std::move(error)) {}  // NOLINT: implicit

    bool ok() const { return v_.index() == 0; }
    explicit operator bool() const { return ok(); }
    T& value() & { return std::get<0>(v_); }
    const T& value() const& { return std::get<0>(v_); }
    T&& value() && { return std::get<0>(std::move(v_)); }
    T* operator->() { return &value(); }
    const T* operator->() const { return &value(); }
    T& operator*() & { return value(); }
    const Error& error() const { return std::get<1>(v_); }

   private:
    std::variant<T, Error> v_;
};

/// Result of an operation that yields nothing but may fail.
struct Ok {};
using Status = Result<Ok>;

}  // namespace ncrev
