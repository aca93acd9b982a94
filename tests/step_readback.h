// A STEP file read back with OpenCASCADE's reader, for tests of what ncrev writes.
#pragma once

#include <TopoDS_Shape.hxx>
#include <cstddef>
#include <filesystem>

namespace ncrev::test {

struct ReadBack {
    TopoDS_Shape shape;
    bool valid = false;  ///< BRepCheck_Analyzer finds no defect
    std::size_t solids = 0, faces = 0;
    double volume = 0;
};

/// Reads `path` (STEPControl_Reader, all roots); an unreadable file gives an empty ReadBack.
ReadBack read_step(const std::filesystem::path& path);

}  // namespace ncrev::test
