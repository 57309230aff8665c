# VTK's own XML readers (python3-vtk9) on a run's cloth.pvd and its .vtp files:
# every frame's points equal the run's frames/frame_NNNNN.obj (same up axis),
# and the wet model's fields are there, one value a point.
#   /usr/bin/python3 vtk_read.py RUN_DIR
import os
import sys
import xml.etree.ElementTree as ET

from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

run = sys.argv[1]
datasets = ET.parse(os.path.join(run, "cloth.pvd")).getroot().find("Collection").findall("DataSet")
frames = sorted(f for f in os.listdir(os.path.join(run, "frames")) if f.endswith(".obj"))
assert len(datasets) == len(frames) > 1, (len(datasets), len(frames))
worst = 0.0
for ds, name in zip(datasets, frames):
    r = vtkXMLPolyDataReader()
    r.SetFileName(os.path.join(run, ds.get("file")))
    r.Update()
    poly = r.GetOutput()
    pts = vtk_to_numpy(poly.GetPoints().GetData())
    want = [[float(t) for t in l.split()[1:4]] for l in open(os.path.join(run, "frames", name)) if l.startswith("v ")]
    assert pts.shape == (len(want), 3), (pts.shape, len(want))
    worst = max(worst, max(abs(a - b) for p, w in zip(pts, want) for a, b in zip(p, w)))
    assert poly.GetNumberOfPolys() > 0
    pd = poly.GetPointData()
    for field in ("contact", "pressure_pa", "adhesion_n", "humidity", "normals", "uv"):
        a = pd.GetArray(field)
        assert a is not None and a.GetNumberOfTuples() == len(want), field
print(f"vtk: {len(datasets)} frames, {len(want)} points, largest difference {worst:.3g} m")
sys.exit(0 if worst < 1e-6 else 1)
