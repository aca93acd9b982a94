#include "brep/check.h"

#include <BRepCheck.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepCheck_Result.hxx>
#include <BRepGProp.hxx>
#include <GProp_GProps.hxx>
#include <TopExp.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <cctype>
#include <sstream>

namespace ncrev::brep_detail {

std::string check_failure(const TopoDS_Shape& shape, std::vector<TopoDS_Shape>* bad,
                          bool parallel) {
    BRepCheck_Analyzer check(shape, Standard_True, parallel ? Standard_True : Standard_False);
    if (check.IsValid()) return {};
    std::string out;
    for (TopAbs_ShapeEnum type :
         {TopAbs_VERTEX, TopAbs_EDGE, TopAbs_WIRE, TopAbs_FACE, TopAbs_SHELL, TopAbs_SOLID}) {
        TopTools_IndexedMapOfShape subs;
        TopExp::MapShapes(shape, type, subs);
        const std::string kind = type == TopAbs_VERTEX  ? "vertex"
                                 : type == TopAbs_EDGE  ? "edge"
                                 : type == TopAbs_WIRE  ? "wire"
                                 : type == TopAbs_FACE  ? "face"
                                 : type == TopAbs_SHELL ? "shell"
                                                        : "solid";
        for (int i = 1; i <= subs.Extent(); ++i) {
            const Handle(BRepCheck_Result) res = check.Result(subs(i));
            if (res.IsNull()) continue;
            std::vector<BRepCheck_Status> statuses(res->Status().begin(), res->Status().end());
            for (res->InitContextIterator(); res->MoreShapeInContext(); res->NextShapeInContext()) {
                for (BRepCheck_Status st : res->StatusOnShape()) statuses.push_back(st);
            }
            bool wrong = false;
            for (BRepCheck_Status st : statuses) {
                if (st == BRepCheck_NoError) continue;
                wrong = true;
                std::ostringstream os;
                BRepCheck::Print(st, os);
                std::string word = os.str();
                while (!word.empty() && std::isspace(static_cast<unsigned char>(word.back()))) {
                    word.pop_back();
                }
                const std::string entry = kind + ": " + word;
                if (out.size() < 300 && out.find(entry) == std::string::npos) {
                    out += (out.empty() ? "" : "; ") + entry;
                }
            }
            if (wrong && bad) bad->push_back(subs(i));
        }
    }
    return out.empty() ? "invalid" : out;
}

double solid_volume(const TopoDS_Shape& shape) {
    GProp_GProps props;
    BRepGProp::VolumeProperties(shape, props, kVolumeRelativeError);
    return props.Mass();
}

}  // namespace ncrev::brep_detail
