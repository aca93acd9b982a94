// Sample parts as the tests mesh them: fine (the default chordal deflection) or coarse.
#pragma once

#include <filesystem>
#include <string_view>
#include <vector>

#include "ncrev/sample.h"

namespace ncrev::test {

constexpr double kFine = kSampleRelativeDeflection;
constexpr double kCoarse = 4 * kSampleRelativeDeflection;
/// Coarse meshes also take larger normal steps (29 degrees, under the 30-degree sharp angle).
constexpr double kCoarseAngular = 0.5;

/// make_sample_part() without the STEP text, at `relative_deflection` (kFine or kCoarse, the
/// coarse one with kCoarseAngular); a failure is a test failure.
SamplePart sample_case(std::string_view name, double relative_deflection);

/// ../shared/corpus/step beside the source tree (absent on a bare clone: tests skip).
std::filesystem::path corpus_step_dir();

/// The STEP files of the corpus (.step / .stp, any case), sorted; empty without the corpus.
std::vector<std::filesystem::path> corpus_steps();

}  // namespace ncrev::test
