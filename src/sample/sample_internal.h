// Internals of the sample module: the part registry, the dimension generator, and the
// tessellation of a solid into a labelled mesh. OpenCASCADE types are fine here.
#pragma once

#include <TopoDS_Shape.hxx>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "ncrev/sample.h"

namespace ncrev::sample_detail {

/// Thrown inside the module when modelling fails; make_sample_part() turns it into an Error.
struct ModelError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// splitmix64 (Steele, Lea, Flood 2014): a tiny PRNG whose output is fixed by its definition,
/// unlike std::uniform_*_distribution, whose output differs between standard libraries.
class SplitMix64 {
   public:
    explicit SplitMix64(std::uint64_t state) : state_(state) {}
    std::uint64_t next() {
        std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
        z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
        z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
        return z ^ (z >> 31);
    }
    /// Uniform in [0, 1), from the top 53 bits.
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

   private:
    std::uint64_t state_;
};

/// The named dimensions of one part build. Seed 0 gives the nominal values; another seed
/// scales each by a factor in [1 - rel, 1 + rel] drawn from the part's own stream.
class Dims {
   public:
    Dims(std::string_view part, std::uint64_t seed);
    /// A length in mm, varied by +-rel and rounded to 0.01 mm (readable, exact in the JSON).
    double length(const char* name, double nominal, double rel = 0.1);
    /// An angle in degrees, varied by +-rel, rounded to 0.01 degree.
    double angle_deg(const char* name, double nominal, double rel = 0.0);
    /// An integer count, nominal for seed 0, else uniform in [lo, hi].
    int count(const char* name, int nominal, int lo, int hi);
    /// A derived value: recorded, not varied.
    double derived(const char* name, double value);

    std::vector<SampleDimension> take() { return std::move(dims_); }

   private:
    double vary(double nominal, double rel);
    SplitMix64 rng_;
    bool vary_;
    std::vector<SampleDimension> dims_;
};

using PartBuilder = TopoDS_Shape (*)(Dims& dims);

struct PartEntry {
    SamplePartInfo info;
    PartBuilder build;
};

/// The registry, in the order of sample_parts().
std::span<const PartEntry> part_entries();

/// Tessellates `solid` (already meshed by BRepMesh_IncrementalMesh) into `part`: mesh,
/// labels, faces, surface table, weld numbers; `face_params` gets each face's surface
/// parameters as named JSON (the truth document's "parameters"). Throws ModelError when a
/// face has no triangulation.
void tessellate_solid(const TopoDS_Shape& solid, SamplePart& part,
                      std::vector<nlohmann::ordered_json>& face_params);

/// Writes the solid as STEP AP214 in mm into a string; empty string on failure.
std::string step_text(const TopoDS_Shape& solid, std::string_view part_name);

/// Turns off OpenCASCADE's default printer (once per process) so nothing reaches stdout.
void silence_occt();

}  // namespace ncrev::sample_detail
