#include "brep/step.h"

#include <unistd.h>

#include <APIHeaderSection_MakeHeader.hxx>
#include <BRep_Tool.hxx>
#include <Geom_Curve.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Message_PrinterOStream.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Writer.hxx>
#include <STEPControl_Controller.hxx>
#include <STEPControl_Reader.hxx>
#include <STEPControl_Writer.hxx>
#include <Standard_Failure.hxx>
#include <StepBasic_Product.hxx>
#include <StepData_StepModel.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TDF_Label.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedDataMapOfShapeListOfShape.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Edge.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Vertex.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <atomic>
#include <mutex>

#include "brep/check.h"

namespace ncrev::brep_detail {

void silence_occt() {
    static std::once_flag once;
    std::call_once(once, [] {
        const Handle(Message_Messenger)& m = Message::DefaultMessenger();
        m->RemovePrinters(STANDARD_TYPE(Message_PrinterOStream));
    });
}

namespace {

const char* schema_name(StepSchema s) {
    switch (s) {
        case StepSchema::kAP203:
            return "AP203";
        case StepSchema::kAP242:
            return "AP242DIS";
        case StepSchema::kAP214:
            break;
    }
    return "AP214IS";
}

Error write_error(ErrorCode code, const std::filesystem::path& path, std::string message) {
    Error e;
    e.code = code;
    e.path = path.string();
    e.message = std::move(message);
    return e;
}

}  // namespace

Status write_step_file(const TopoDS_Shape& shape, const std::filesystem::path& path,
                       const StepWriteOptions& options) {
    silence_occt();
    static std::mutex step_mutex;  // Interface_Static is process-wide state
    const std::lock_guard<std::mutex> lock(step_mutex);
    static std::atomic<unsigned> counter{0};
    const std::filesystem::path dir =
        path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
    std::string tmp_name = ".";
    tmp_name.append(path.filename().string())
        .append(".tmp")
        .append(std::to_string(::getpid()))
        .append("-")
        .append(std::to_string(counter++));
    const std::filesystem::path tmp = dir / tmp_name;
    try {
        STEPControl_Controller::Init();
        Interface_Static::SetCVal("write.step.schema", schema_name(options.schema));
        // The shape's coordinates are in the file's unit: tell OpenCASCADE so, or it takes
        // them as millimetres and scales them into the declared unit.
        const char* unit = options.unit == Unit::kInch ? "INCH" : "MM";
        Interface_Static::SetCVal("write.step.unit", unit);
        // Process-wide, and read by STEP readers too: restored when done.
        struct RestoreCascadeUnit {
            std::string old = Interface_Static::CVal("xstep.cascade.unit");
            ~RestoreCascadeUnit() { Interface_Static::SetCVal("xstep.cascade.unit", old.c_str()); }
        } restore;
        Interface_Static::SetCVal("xstep.cascade.unit", unit);
        // Header name and time stamp, and the product named as given (OCCT names it "<name>
        // <process-wide counter>").
        const auto name_model = [&](const Handle(StepData_StepModel) & model) {
            APIHeaderSection_MakeHeader header(model);
            const Handle(TCollection_HAsciiString) name =
                new TCollection_HAsciiString(options.product_name.c_str());
            header.SetName(name);
            if (!options.timestamp.empty()) {
                header.SetTimeStamp(new TCollection_HAsciiString(options.timestamp.c_str()));
            }
            for (int i = 1; i <= model->NbEntities(); ++i) {
                const Handle(StepBasic_Product) product =
                    Handle(StepBasic_Product)::DownCast(model->Value(i));
                if (product.IsNull()) continue;
                product->SetId(name);
                product->SetName(name);
            }
        };
        IFSelect_ReturnStatus status = IFSelect_RetFail;
        if (options.face_colors.empty()) {
            STEPControl_Writer writer;
            if (writer.Transfer(shape, STEPControl_AsIs) != IFSelect_RetDone) {
                return write_error(ErrorCode::kBadValue, path,
                                   "OpenCASCADE could not transfer the shape to STEP");
            }
            name_model(writer.Model());
            status = writer.Write(tmp.c_str());
        } else {
            // Colors need the XDE document: the shape, each colored face a sub-shape label.
            Handle(TDocStd_Document) doc;
            XCAFApp_Application::GetApplication()->NewDocument("MDTV-XCAF", doc);
            XCAFDoc_DocumentTool::SetLengthUnit(doc, options.unit == Unit::kInch ? 0.0254 : 0.001);
            const Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
            const Handle(XCAFDoc_ColorTool) colors = XCAFDoc_DocumentTool::ColorTool(doc->Main());
            const TDF_Label root = shapes->AddShape(shape, false);
            const auto color = [](std::uint32_t rgb) {
                return Quantity_Color(((rgb >> 16) & 0xFF) / 255.0, ((rgb >> 8) & 0xFF) / 255.0,
                                      (rgb & 0xFF) / 255.0, Quantity_TOC_sRGB);
            };
            colors->SetColor(root, color(options.shape_color), XCAFDoc_ColorSurf);
            for (const auto& [face, rgb] : options.face_colors) {
                const TDF_Label sub = shapes->AddSubShape(root, face);
                if (sub.IsNull()) continue;
                colors->SetColor(sub, color(rgb), XCAFDoc_ColorSurf);
            }
            STEPCAFControl_Writer writer;
            writer.SetColorMode(true);
            writer.SetNameMode(false);
            if (!writer.Transfer(doc, STEPControl_AsIs)) {
                return write_error(ErrorCode::kBadValue, path,
                                   "OpenCASCADE could not transfer the shape to STEP");
            }
            name_model(writer.ChangeWriter().Model());
            status = writer.Write(tmp.c_str());
        }
        if (status != IFSelect_RetDone) {
            std::error_code ec;
            std::filesystem::remove(tmp, ec);
            return write_error(ErrorCode::kCannotWrite, path,
                               "cannot write a STEP file in " + dir.string());
        }
    } catch (const Standard_Failure& f) {
        std::error_code ec;
        std::filesystem::remove(tmp, ec);
        return write_error(ErrorCode::kBadValue, path,
                           std::string("OpenCASCADE failed writing STEP: ") + f.GetMessageString());
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        const std::string why = ec.message();  // before remove() overwrites ec
        std::filesystem::remove(tmp, ec);
        return write_error(ErrorCode::kCannotWrite, path, "cannot rename into place: " + why);
    }
    return Ok{};
}

ReadBack step_read_back(const std::filesystem::path& path, int expected_solids) {
    silence_occt();
    ReadBack out;
    const auto place = [&](const gp_Pnt& p) {
        if (out.places.size() < kReadBackPlaces) out.places.push_back({p.X(), p.Y(), p.Z()});
    };
    try {
        STEPControl_Reader reader;
        if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) {
            out.problem = "OpenCASCADE cannot read it";
            return out;
        }
        reader.TransferRoots();
        const TopoDS_Shape shape = reader.OneShape();
        TopTools_IndexedMapOfShape solids;
        TopExp::MapShapes(shape, TopAbs_SOLID, solids);
        if (solids.Extent() != expected_solids) {
            out.problem =
                std::to_string(solids.Extent()) + " solids for " + std::to_string(expected_solids);
        }
        // Edges of one face only (not seams): where the reader's healing opened the shell.
        TopTools_IndexedDataMapOfShapeListOfShape edge_faces;
        TopExp::MapShapesAndUniqueAncestors(shape, TopAbs_EDGE, TopAbs_FACE, edge_faces);
        for (int i = 1; i <= edge_faces.Extent(); ++i) {
            const TopoDS_Edge& e = TopoDS::Edge(edge_faces.FindKey(i));
            const TopTools_ListOfShape& fs = edge_faces.FindFromIndex(i);
            if (BRep_Tool::Degenerated(e) || fs.Extent() != 1 ||
                BRep_Tool::IsClosed(e, TopoDS::Face(fs.First()))) {
                continue;
            }
            double a = 0, b = 0;
            const Handle(Geom_Curve) c = BRep_Tool::Curve(e, a, b);
            place(c.IsNull() ? BRep_Tool::Pnt(TopExp::FirstVertex(e)) : c->Value(0.5 * (a + b)));
        }
        // Where the checker finds the shape wrong: a vertex of each defective face (one
        // analysis of the whole shape; its results say which faces are wrong).
        std::vector<TopoDS_Shape> bad;
        if (const std::string why = check_failure(shape, &bad); !why.empty()) {
            if (out.problem.empty()) out.problem = "BRepCheck_Analyzer: " + why;
            for (const TopoDS_Shape& b : bad) {
                if (b.ShapeType() != TopAbs_FACE) continue;
                TopExp_Explorer v(b, TopAbs_VERTEX);
                if (v.More()) place(BRep_Tool::Pnt(TopoDS::Vertex(v.Current())));
            }
        }
    } catch (const Standard_Failure& f) {
        out.problem = std::string("OpenCASCADE fails reading it: ") + f.GetMessageString();
    }
    return out;
}

}  // namespace ncrev::brep_detail
