#include "sample_cases.h"

#include <gtest/gtest.h>

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

}  // namespace ncrev::test
