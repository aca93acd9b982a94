#include "scratch.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <system_error>

namespace ncrev::test {
namespace {

std::filesystem::path scratch_path() {
    return std::filesystem::temp_directory_path() / ("ncrev_test." + std::to_string(::getpid()));
}

/// Removes the folder after the last test; listing the tests never makes it.
class RemoveScratch : public ::testing::Environment {
   public:
    void TearDown() override {
        std::error_code ec;
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
