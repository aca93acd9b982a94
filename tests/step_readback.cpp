#include "step_readback.h"

#include <BRepCheck_Analyzer.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>

#include "brep/check.h"

namespace ncrev::test {

ReadBack read_step(const std::filesystem::path& path) {
    ReadBack r;
    STEPControl_Reader reader;
    if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) return r;
    reader.TransferRoots();
    r.shape = reader.OneShape();
    r.valid = BRepCheck_Analyzer(r.shape).IsValid();
    TopTools_IndexedMapOfShape solids, faces;
    TopExp::MapShapes(r.shape, TopAbs_SOLID, solids);
    TopExp::MapShapes(r.shape, TopAbs_FACE, faces);
    r.solids = static_cast<std::size_t>(solids.Extent());
    r.faces = static_cast<std::size_t>(faces.Extent());
    r.volume = brep_detail::solid_volume(r.shape);
    return r;
}

}  // namespace ncrev::test
