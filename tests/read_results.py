"""Opens a Sinew results folder with real readers, as users do, and checks what they see against the
HDF5 data (read with h5py) and the source mesh (read with meshio):
  - meshio reads the XDMF time series: the number of steps, the field names, the values;
  - ParaView's XDMF reader: the time steps, the arrays, the point count and a deformed bound;
  - the mesh Sinew wrote, put back in file order by /node_gid, is the .msh file as meshio reads it.
Usage: read_results.py RESULTS_DIR STEPS MESH_FILE
"""
import glob
import os
import sys

import h5py
import meshio
import numpy as np

results, steps, mesh_file = sys.argv[1], int(sys.argv[2]), sys.argv[3]
xdmf = glob.glob(os.path.join(results, "*.xdmf"))
assert len(xdmf) == 1, f"expected one .xdmf in {results}, found {xdmf}"
xdmf = xdmf[0]

with h5py.File(os.path.join(results, "mesh.h5"), "r") as m:
    X = m["/coordinates"][...]
    conn = m["/connectivity"][...]
    gid = m["/node_gid"][...]
    egid = m["/element_gid"][...]

# 1. meshio's XDMF time-series reader.
with meshio.xdmf.TimeSeriesReader(xdmf) as r:
    points, cells = r.read_points_cells()
    assert np.array_equal(points, X), "meshio: points differ from mesh.h5"
    assert cells[0].type == "tetra" and np.array_equal(cells[0].data, conn), "meshio: connectivity differs"
    assert r.num_steps == steps + 1, f"meshio: {r.num_steps} steps, expected {steps + 1} (rest + {steps})"
    for k in range(r.num_steps):
        t, point_data, cell_data = r.read_data(k)
        assert set(point_data) == {"displacement"}, f"meshio: point fields {sorted(point_data)}"
        assert set(cell_data) == {"J", "energy_density"}, f"meshio: cell fields {sorted(cell_data)}"
        with h5py.File(os.path.join(results, f"step_{k:06d}.h5"), "r") as s:
            assert np.array_equal(point_data["displacement"], s["/displacement"][...]), f"step {k}: displacement"
            assert np.array_equal(cell_data["J"][0].ravel(), s["/J"][...].ravel()), f"step {k}: J"
            assert np.array_equal(cell_data["energy_density"][0].ravel(), s["/energy_density"][...].ravel()), \
                f"step {k}: energy_density"
            # position = X + u, row by row (the XDMF geometry of each step)
            assert np.allclose(s["/position"][...], X + s["/displacement"][...], rtol=0, atol=1e-14), f"step {k}: position"
            assert abs(t - s.attrs["load"]) < 1e-12, f"step {k}: time {t} vs load {s.attrs['load']}"
last_u = point_data["displacement"]
assert np.abs(last_u).max() > 0.1, "the last step is not deformed"
print(f"meshio: {r.num_steps} steps, {len(points)} points, {len(conn)} cells, fields displacement, J, energy_density")

# 2. The source mesh, read by meshio, against what Sinew wrote (rows in output order, ids in file order).
src = meshio.read(mesh_file)
tets = np.concatenate([c.data for c in src.cells if c.type == "tetra"])
used = np.unique(tets)  # Sinew numbers the nodes that elements use, in file order
assert len(used) == len(X), f"{len(used)} nodes used in the file, Sinew wrote {len(X)}"
assert np.array_equal(src.points[used[gid]], X), "node coordinates differ from the .msh file"
compact = np.searchsorted(used, tets)
wrote = gid[conn]  # each written element as file-order node ids
for e in range(len(conn)):  # same element, same nodes (a reoriented element may list them permuted)
    assert sorted(wrote[e]) == sorted(compact[egid[e]]), f"element {egid[e]} differs from the .msh file"
print(f"meshio: the .msh file's {len(X)} nodes and {len(conn)} tets match mesh.h5")

# 3. ParaView's own reader.
from paraview import servermanager as sm  # noqa: E402
from paraview import simple as pv  # noqa: E402

reader = pv.OpenDataFile(xdmf)
times = list(reader.TimestepValues)
assert len(times) == steps + 1, f"ParaView: {len(times)} time steps, expected {steps + 1}"
reader.UpdatePipeline(times[-1])
info = reader.GetDataInformation()
assert info.GetNumberOfPoints() == len(X), f"ParaView: {info.GetNumberOfPoints()} points"
assert info.GetNumberOfCells() == len(conn), f"ParaView: {info.GetNumberOfCells()} cells"
assert "displacement" in reader.PointData.keys() and "J" in reader.CellData.keys(), "ParaView: arrays missing"
with h5py.File(os.path.join(results, f"step_{steps:06d}.h5"), "r") as s:
    J = s["/J"][...]
    pos = s["/position"][...]
lo, hi = reader.CellData["J"].GetRange()
assert abs(lo - J.min()) < 1e-12 and abs(hi - J.max()) < 1e-12, f"ParaView: J range {lo, hi} vs {J.min(), J.max()}"
b = info.GetBounds()
assert abs(b[1] - pos[:, 0].max()) < 1e-12, "ParaView: the geometry is not the deformed position"
print(f"ParaView: {len(times)} time steps, J in [{lo:.4f}, {hi:.4f}], deformed x max {b[1]:.4f}")
