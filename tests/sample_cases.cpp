#include "sample_cases.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <string>

namespace ncrev::test {

SamplePart sample_case(std::string_view name, double relative_deflection) {
    SampleOptions so;
    so.with_step = false;
    so.relative_deflection = relative_deflection;
    if (relative_deflection > kSampleRelativeDeflection) so.angular_deflection = kCoarseAngular;
    Result<SamplePart> made = make_sample_part(name, so);
    EXPECT_TRUE(made.ok()) << name;
    return made.ok() ? std::move(made).value() : SamplePart{};
}

std::filesystem::path corpus_step_dir() {
    return std::filesystem::path(NCREV_SOURCE_DIR) / ".." / "shared" / "corpus" / "step";
}

std::vector<std::filesystem::path> corpus_steps() {
    std::vector<std::filesystem::path> out;
    if (!std::filesystem::is_directory(corpus_step_dir())) return out;
    for (const auto& e : std::filesystem::directory_iterator(corpus_step_dir())) {
        std::string ext = e.path().extension().string();
        std::transform(ext.begin(), ext.end(), ext.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        if (ext == ".step" || ext == ".stp") out.push_back(e.path());
    }
    std::sort(out.begin(), out.end());
    return out;
}

}  // namespace ncrev::test
