// One scratch folder per test process for the files tests write, removed when the process
// ends: ctest runs every test in a process of its own, two checkouts may test at once, and
// nothing a test writes should outlive it.
#pragma once

#include <filesystem>

namespace ncrev::test {

/// The folder `ncrev_test.<pid>` under the system's temporary folder, made on first use and
/// removed (with all it holds) when the test program ends with every test passed. A test
/// must not remove it (it is made once per process): use a folder of its own inside.
const std::filesystem::path& scratch_dir();

}  // namespace ncrev::test
