// make_sample_part(): build a part, check it, tessellate it, and describe it (truth JSON,
// STEP); write_sample_part(): the five files, each written atomically.
#include <unistd.h>

#include <BRepBndLib.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <atomic>
#include <fstream>
#include <optional>
#include <sstream>

#include "brep/check.h"
#include "brep/step.h"
#include "ncrev/io.h"
#include "sample/sample_internal.h"

namespace ncrev {

namespace sd = sample_detail;
using Json = nlohmann::ordered_json;

namespace {

Error make_error(ErrorCode code, std::string message) {
    Error e;
    e.code = code;
    e.message = std::move(message);
    return e;
}

const sd::PartEntry* find_part(std::string_view name) {
    for (const sd::PartEntry& p : sd::part_entries()) {
        if (p.info.name == name) return &p;
    }
    return nullptr;
}

/// The one solid of a modelling result (booleans return compounds).
TopoDS_Shape single_solid(const TopoDS_Shape& shape) {
    TopTools_IndexedMapOfShape solids;
    TopExp::MapShapes(shape, TopAbs_SOLID, solids);
    if (solids.Extent() != 1) {
        throw sd::ModelError("modelling gave " + std::to_string(solids.Extent()) +
                             " solids, expected 1");
    }
    return solids(1);
}

/// Every non-degenerate edge is used exactly twice by the faces (a seam twice by one face).
bool is_closed(const TopoDS_Shape& solid) {
    TopTools_IndexedMapOfShape edges;
    TopExp::MapShapes(solid, TopAbs_EDGE, edges);
    std::vector<int> uses(static_cast<std::size_t>(edges.Extent()) + 1, 0);
    for (TopExp_Explorer f(solid, TopAbs_FACE); f.More(); f.Next()) {
        for (TopExp_Explorer e(f.Current(), TopAbs_EDGE); e.More(); e.Next()) {
            ++uses[static_cast<std::size_t>(edges.FindIndex(e.Current()))];
        }
    }
    for (int i = 1; i <= edges.Extent(); ++i) {
        if (BRep_Tool::Degenerated(TopoDS::Edge(edges(i)))) continue;
        if (uses[static_cast<std::size_t>(i)] != 2) return false;
    }
    return true;
}

Json jvec(const Vec3& p) { return Json::array({p.x, p.y, p.z}); }

std::string truth_document(const SamplePart& part, std::string_view description,
                           const std::vector<Json>& face_params) {
    Json dims = Json::object();
    for (const SampleDimension& d : part.dimensions) dims[d.name] = d.value;
    Json faces = Json::array();
    for (const SampleFace& f : part.faces) {
        faces.push_back({{"index", f.index},
                         {"kind", f.kind},
                         {"sre_surface", f.surface},
                         {"parameters", face_params[f.index]},
                         {"area", f.area},
                         {"facets", f.num_facets}});
    }
    const SampleSolid& s = part.solid;
    const SampleWeld& w = part.weld;
    Json doc = {
        {"format", "ncrev-sample-truth"},
        {"version", 1},
        {"part", part.name},
        {"description", description},
        {"seed", part.seed},
        {"unit", "mm"},
        {"dimensions", dims},
        {"conventions",
         {{"faces", "numbered from 0 in OpenCASCADE TopExp::MapShapes order"},
          {"labels", "NAME.labels: the face index of every facet, one per line, STL order"},
          {"sre",
           "color: one tool per surface kind; cut: the face index; surface: index "
           "into the SRE surface table, -1 for free-form faces"},
          {"plane", "point, normal (unit, outward)"},
          {"cylinder", "axis_point, axis_dir (unit), radius"},
          {"cone",
           "apex, axis_dir (unit, the radius grows along it), half_angle (rad); "
           "sre: the SRE record (point on the axis, axis_dir, radius of the section "
           "through the point, half_angle)"},
          {"sphere", "center, radius"},
          {"torus", "center, axis_dir (unit), major_radius, minor_radius"},
          {"convex", "the outward normal points away from the axis / center / tube center"}}},
        {"tessellation",
         {{"deflection", part.deflection},
          {"deflection_rule", part.deflection_rule},
          {"angular_deflection", part.angular_deflection},
          {"vertices", part.mesh.points.size()},
          {"facets", part.mesh.triangles.size()},
          {"weld",
           {{"merged_nodes", w.merged_nodes},
            {"float32_mismatches", w.float32_mismatches},
            {"max_gap", w.max_gap},
            {"coincident_merges", w.coincident_merges},
            {"degenerate_facets_dropped", w.degenerate_facets_dropped}}}}},
        {"solid",
         {{"valid", s.valid},
          {"closed", s.closed},
          {"volume", s.volume},
          {"area", s.area},
          {"bbox", {{"min", jvec(s.bbox.min)}, {"max", jvec(s.bbox.max)}}},
          {"faces", s.num_faces},
          {"edges", s.num_edges},
          {"vertices", s.num_vertices}}},
        {"faces", faces},
    };
    return doc.dump(1) + "\n";
}

}  // namespace

namespace sample_detail {

void silence_occt() { brep_detail::silence_occt(); }

std::string step_text(const TopoDS_Shape& solid, std::string_view part_name) {
    // OCCT writes STEP only to a file: a private temporary one, read back and removed.
    static std::atomic<unsigned> counter{0};
    std::error_code ec;
    const std::filesystem::path tmp =
        std::filesystem::temp_directory_path(ec) /
        ("ncrev-sample-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".step");
    if (ec) return {};
    brep_detail::StepWriteOptions options;
    options.product_name = std::string(part_name);
    std::string text;
    if (brep_detail::write_step_file(solid, tmp, options).ok()) {
        std::ifstream in(tmp, std::ios::binary);
        std::ostringstream ss;
        ss << in.rdbuf();
        text = ss.str();
    }
    std::filesystem::remove(tmp, ec);
    return text;
}

}  // namespace sample_detail

std::span<const SamplePartInfo> sample_parts() {
    static const std::vector<SamplePartInfo> infos = [] {
        std::vector<SamplePartInfo> v;
        for (const sd::PartEntry& p : sd::part_entries()) v.push_back(p.info);
        return v;
    }();
    return infos;
}

bool is_sample_part(std::string_view name) { return find_part(name) != nullptr; }

namespace {

bool options_ok(const SampleOptions& options) {
    return options.angular_deflection > 0 && std::isfinite(options.angular_deflection) &&
           std::isfinite(options.deflection) && options.relative_deflection > 0 &&
           std::isfinite(options.relative_deflection);
}

/// The numbers of `solid`, its tessellation with face labels, the truth document and (with
/// options.with_step) the STEP text, into `part`. Throws sd::ModelError or Standard_Failure;
/// an error is returned for a solid that is not valid and closed when `require_valid`.
std::optional<Error> build_part(const TopoDS_Shape& solid, const SampleOptions& options,
                                std::string_view description, bool require_valid,
                                SamplePart& part) {
    SampleSolid& s = part.solid;
    GProp_GProps sprops;
    BRepGProp::SurfaceProperties(solid, sprops);
    s.volume = brep_detail::solid_volume(solid);
    s.area = sprops.Mass();
    Bnd_Box box;
    BRepBndLib::AddOptimal(solid, box, /*useTriangulation=*/false,
                           /*useShapeTolerance=*/false);
    double x0 = 0, y0 = 0, z0 = 0, x1 = 0, y1 = 0, z1 = 0;
    box.Get(x0, y0, z0, x1, y1, z1);
    s.bbox.add(Vec3{x0, y0, z0});
    s.bbox.add(Vec3{x1, y1, z1});
    TopTools_IndexedMapOfShape faces, edges, vertices;
    TopExp::MapShapes(solid, TopAbs_FACE, faces);
    TopExp::MapShapes(solid, TopAbs_EDGE, edges);
    TopExp::MapShapes(solid, TopAbs_VERTEX, vertices);
    s.num_faces = static_cast<std::uint64_t>(faces.Extent());
    s.num_edges = static_cast<std::uint64_t>(edges.Extent());
    s.num_vertices = static_cast<std::uint64_t>(vertices.Extent());
    s.valid = BRepCheck_Analyzer(solid).IsValid();
    s.closed = is_closed(solid);
    if (require_valid && (!s.valid || !s.closed || !(s.volume > 0))) {
        return make_error(ErrorCode::kBadValue, "part '" + part.name + "' (seed " +
                                                    std::to_string(options.seed) +
                                                    ") is not a valid closed solid");
    }

    part.deflection = options.deflection > 0 ? options.deflection
                                             : options.relative_deflection * s.bbox.diagonal();
    {
        std::ostringstream rule;
        if (options.deflection > 0) {
            rule << "given";
        } else {
            rule << options.relative_deflection << " x bounding-box diagonal";
        }
        part.deflection_rule = rule.str();
    }
    BRepMesh_IncrementalMesh mesher(solid, part.deflection, /*isRelative=*/false,
                                    part.angular_deflection, /*isInParallel=*/false);
    if (!mesher.IsDone()) throw sd::ModelError("meshing failed");
    std::vector<Json> face_params;
    sd::tessellate_solid(solid, part, face_params);
    part.truth_json = truth_document(part, description, face_params);
    if (options.with_step) {
        part.step = sd::step_text(solid, part.name);
        if (part.step.empty()) {
            return make_error(ErrorCode::kCannotWrite,
                              "cannot produce the STEP text of '" + part.name + "'");
        }
    }
    return std::nullopt;
}

}  // namespace

Result<SamplePart> make_sample_part(std::string_view name, const SampleOptions& options) {
    const sd::PartEntry* entry = find_part(name);
    if (entry == nullptr) {
        return make_error(ErrorCode::kBadValue, "unknown sample part '" + std::string(name) + "'");
    }
    if (!options_ok(options)) {
        return make_error(ErrorCode::kBadValue,
                          "deflection must be finite, angular and relative deflection positive");
    }
    sd::silence_occt();
    SamplePart part;
    part.name = std::string(name);
    part.seed = options.seed;
    part.angular_deflection = options.angular_deflection;
    try {
        sd::Dims dims(name, options.seed);
        const TopoDS_Shape solid = single_solid(entry->build(dims));
        part.dimensions = dims.take();
        if (auto e = build_part(solid, options, entry->info.description, true, part)) return *e;
    } catch (const Standard_Failure& e) {
        return make_error(ErrorCode::kBadValue, "part '" + part.name + "': OpenCASCADE: " +
                                                    std::string(e.GetMessageString()));
    } catch (const std::exception& e) {
        return make_error(ErrorCode::kBadValue, "part '" + part.name + "': " + e.what());
    }
    return part;
}

Result<SamplePart> sample_from_step(const std::filesystem::path& path,
                                    const SampleOptions& options) {
    if (!options_ok(options)) {
        return make_error(ErrorCode::kBadValue,
                          "deflection must be finite, angular and relative deflection positive");
    }
    sd::silence_occt();
    SamplePart part;
    part.name = path.stem().string();
    part.angular_deflection = options.angular_deflection;
    try {
        STEPControl_Reader reader;
        if (reader.ReadFile(path.string().c_str()) != IFSelect_RetDone) {
            Error e = make_error(ErrorCode::kBadSyntax, "not a STEP file OpenCASCADE can read");
            e.path = path.string();
            return e;
        }
        reader.TransferRoots();
        const TopoDS_Shape shape = reader.OneShape();
        TopTools_IndexedMapOfShape solids;
        TopExp::MapShapes(shape, TopAbs_SOLID, solids);
        if (solids.Extent() == 0) {
            Error e = make_error(ErrorCode::kBadValue, "the STEP file holds no solid");
            e.path = path.string();
            return e;
        }
        // The largest solid (an assembly's main part; most files hold one).
        int best = 1;
        double best_volume = -1;
        for (int i = 1; i <= solids.Extent(); ++i) {
            GProp_GProps props;
            BRepGProp::VolumeProperties(solids(i), props);
            if (std::abs(props.Mass()) > best_volume)
                best_volume = std::abs(props.Mass()), best = i;
        }
        std::string description = "solid from " + path.filename().string();
        if (solids.Extent() > 1) {
            description += " (the largest of " + std::to_string(solids.Extent()) + ")";
        }
        if (auto e = build_part(solids(best), options, description, false, part)) return *e;
    } catch (const Standard_Failure& e) {
        Error err =
            make_error(ErrorCode::kBadValue, "OpenCASCADE: " + std::string(e.GetMessageString()));
        err.path = path.string();
        return err;
    } catch (const std::exception& e) {
        Error err = make_error(ErrorCode::kBadValue, e.what());
        err.path = path.string();
        return err;
    }
    return part;
}

namespace {

Status write_text(const std::filesystem::path& path, std::string_view text) {
    return write_file_atomic(
        path,
        std::span<const std::byte>(reinterpret_cast<const std::byte*>(text.data()), text.size()));
}

}  // namespace

Result<SampleFiles> write_sample_part(const SamplePart& part, const std::filesystem::path& dir) {
    SampleFiles files;
    files.folder = dir / part.name;
    std::error_code ec;
    std::filesystem::create_directories(files.folder, ec);
    if (ec) {
        Error e = make_error(ErrorCode::kCannotWrite, "cannot create folder: " + ec.message());
        e.path = files.folder.string();
        return e;
    }
    const auto file = [&](const char* ext) { return files.folder / (part.name + ext); };
    files.stl = file(".stl");
    files.sre = file(".sre");
    files.labels = file(".labels");
    files.truth = file(".truth.json");

    const std::string header = "ncrev sample " + part.name + " seed " + std::to_string(part.seed);
    const std::vector<std::byte> stl =
        encode_stl_binary(part.mesh.points, part.mesh.triangles, header);
    if (Status st = write_file_atomic(files.stl, stl); !st) return st.error();
    if (Status st = write_text(files.sre, encode_sre(part.mesh)); !st) return st.error();
    std::string labels;
    labels.reserve(part.labels.size() * 3);
    for (const std::int32_t l : part.labels) {
        labels += std::to_string(l);
        labels += '\n';
    }
    if (Status st = write_text(files.labels, labels); !st) return st.error();
    if (Status st = write_text(files.truth, part.truth_json); !st) return st.error();
    if (!part.step.empty()) {
        files.step = file(".step");
        if (Status st = write_text(files.step, part.step); !st) return st.error();
    }
    return files;
}

}  // namespace ncrev
