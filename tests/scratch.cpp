#include "scratch.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <system_error>

namespace ncrev::test {
namespace {

std::filesystem::path scratch_path() {
    return std::filesystem::temp_directory_path() / ("ncrev_test." + std::to_string(::getpid()));
}

/// Removes the folder after the last test, unless a test failed: then its files are kept for
/// a look, and where they are is said. Listing the tests never makes it.
class RemoveScratch : public ::testing::Environment {
   public:
    void TearDown() override {
        std::error_code ec;
        if (!std::filesystem::exists(scratch_path(), ec)) return;
        if (!::testing::UnitTest::GetInstance()->Passed()) {
            std::fprintf(stderr, "the failed tests' files are kept in %s\n",
                         scratch_path().string().c_str());
            return;
        }
        std::filesystem::remove_all(scratch_path(), ec);
    }
};

const ::testing::Environment* const kRemoveScratch =
    ::testing::AddGlobalTestEnvironment(new RemoveScratch);

}  // namespace

const std::filesystem::path& scratch_dir() {
    static const std::filesystem::path dir = [] {
        auto d = scratch_path();
        std::filesystem::create_directories(d);
        return d;
    }();
    return dir;
}

}  // namespace ncrev::test
