# FreeCAD's mesh-to-STEP chain, the peer of `ncrev reverse`, timed stage by stage:
# Mesh.Mesh (read) -> Part.Shape.makeShapeFromMesh (one face per facet) -> Part.makeSolid ->
# removeSplitter (merges coplanar faces: the peer of --method planar) -> exportStep.
# Optional (FreeCAD is not in CI). Run with FreeCAD's console, inputs in the environment:
#   NCREV_IN=mesh.stl NCREV_OUT=out.step freecadcmd bench/freecad_reverse.py
# Prints one JSON line.
import json
import os
import time

import Mesh
import Part

path = os.environ["NCREV_IN"]
out = os.environ["NCREV_OUT"]
times = {}
t = time.time()
mesh = Mesh.Mesh(path)
times["read"] = time.time() - t
t = time.time()
shape = Part.Shape()
shape.makeShapeFromMesh(mesh.Topology, 0.05)
times["shape_from_mesh"] = time.time() - t
t = time.time()
solid = Part.makeSolid(shape)
times["make_solid"] = time.time() - t
t = time.time()
refined = solid.removeSplitter()
times["remove_splitter"] = time.time() - t
t = time.time()
refined.exportStep(out)
times["export_step"] = time.time() - t
print(json.dumps({"facets": mesh.CountFacets, "faces": len(refined.Faces),
                  "valid": refined.isValid(), "volume": refined.Volume,
                  "seconds": times, "total": sum(times.values())}))
