"""Checks restarted results as ParaView shows them (restart_layout_test.sh): every time step of the
XDMF index, opened with ParaView's reader, is the body of an uninterrupted 1-rank run at that step
(compared by sorted element centroids, which any row order leaves alone), and every step file is
paired with the mesh file of its own layout.
Usage: read_layout.py WORKDIR
"""
import glob
import os
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np

work = sys.argv[1]


def centroids(points, cells):
    c = points[cells].mean(axis=1)
    return c[np.lexsort(c.T[::-1])]


ref = {}
with h5py.File(f"{work}/reference/mesh.h5", "r") as m:
    conn = m["/connectivity"][...]
for f in sorted(glob.glob(f"{work}/reference/step_*.h5")):
    with h5py.File(f, "r") as s:
        ref[int(s.attrs["step"])] = centroids(s["/position"][...], conn)
size = np.abs(ref[max(ref)]).max()

from paraview import servermanager as sm  # noqa: E402
from paraview import simple as pv  # noqa: E402
from vtk.util.numpy_support import vtk_to_numpy  # noqa: E402

for folder, first in (("same", 0), ("new", 3)):
    xdmf = glob.glob(f"{work}/{folder}/*.xdmf")[0]
    # Each grid's connectivity file has the layout of its geometry file.
    grids = ET.parse(xdmf).getroot().iter("Grid")
    pairs = unmarked = 0
    for g in grids:
        if g.get("GridType") != "Uniform":
            continue
        topo = g.find("Topology/DataItem").text.split(":")[0]
        geom = g.find("Geometry/DataItem").text.split(":")[0]
        with h5py.File(f"{work}/{folder}/{topo}", "r") as t, h5py.File(f"{work}/{folder}/{geom}", "r") as s:
            lt, ls = t.attrs.get("layout"), s.attrs.get("layout")
            if lt is not None and ls is not None:  # required below, after what ParaView shows
                assert lt == ls, f"{folder}: {geom} is paired with {topo} of another layout"
            unmarked += (lt is None) + (ls is None)
        pairs += 1
    reader = pv.OpenDataFile(xdmf)
    times = list(reader.TimestepValues)
    steps = [round(t * 4) for t in times]
    assert steps == list(range(first, 5)), f"{folder}: ParaView sees steps {steps}"
    assert pairs == len(steps)
    worst = 0.0
    for t, k in zip(times, steps):
        reader.UpdatePipeline(t)
        grid = sm.Fetch(reader)
        pts = vtk_to_numpy(grid.GetPoints().GetData())
        npe = grid.GetCell(0).GetNumberOfPoints()
        cells = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, npe)
        d = np.abs(centroids(pts, cells) - ref[k]).max() / size
        worst = max(worst, d)
        assert d < 1e-6, f"{folder}, step {k}: ParaView's body differs from the 1-rank run's by {d:.2e} (scrambled?)"
    assert unmarked == 0, f"{folder}: {unmarked} mesh or step files without a layout attribute"
    print(f"{folder}: {len(steps)} steps as ParaView shows them match the 1-rank run to {worst:.1e}; mesh files paired by layout")
# The folders' mesh files: the 2-rank run's mesh.h5 and, in "same", the 1-rank restart's own.
same_meshes = sorted(os.path.basename(f) for f in glob.glob(f"{work}/same/mesh*.h5"))
assert same_meshes == ["mesh.h5", "mesh_layout1.h5"], f"mesh files in the restarted folder: {same_meshes}"
with h5py.File(f"{work}/same/mesh.h5", "r") as a, h5py.File(f"{work}/same/mesh_layout1.h5", "r") as b:
    assert not np.array_equal(a["/node_gid"][...], b["/node_gid"][...]), \
        "2 ranks and 1 rank wrote the same row order: this test would not see a wrong pairing"
new_meshes = sorted(os.path.basename(f) for f in glob.glob(f"{work}/new/mesh*.h5"))
assert new_meshes == ["mesh.h5"], f"mesh files in the new folder: {new_meshes}"

print("restart on another number of ranks ok")
