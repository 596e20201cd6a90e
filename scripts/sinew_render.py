"""Renders Sinew results to PNG with ParaView's own Python (run through scripts/sinew-render).

The results folder's XDMF index is opened with ParaView's reader, exactly as a user opening it in
ParaView would; each chosen step is shown deformed, coloured by a cell field (J by default) with a
colour bar, under one fixed camera that frames every step of the run. Several steps form a strip, side
by side in one picture, each labelled with its step and load.
"""
import argparse
import glob
import os
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np


def fail(msg):
    print("sinew-render: " + msg, file=sys.stderr)
    sys.exit(2)


def parse_args(argv):
    p = argparse.ArgumentParser(prog="sinew-render", description=__doc__.split("\n\n")[0])
    p.add_argument("results", nargs="+",
                   help="a results folder of sinew (holds NAME.xdmf, mesh.h5, step_*.h5); several folders are "
                        "shown side by side at the same step choice (a comparison of models, like the paper's Fig. 5)")
    p.add_argument("--labels", default=None, help="comma list of labels for several folders (default: folder names)")
    p.add_argument("--steps", default="last",
                   help="which steps: 'last' (default), 'first', 'all', a comma list of step numbers, "
                        "or 'strip:N' for N steps evenly spread from the first to the last")
    p.add_argument("--field", default="J", choices=["J", "energy_density", "displacement", "contact_pressure", "activation"],
                   help="colour by this field (default J = det F: volume change; contact_pressure where the run "
                        "had contact: where flesh presses on flesh or on a collider)")
    p.add_argument("--range", default=None, help="colour range 'lo,hi' (default: over the shown steps)")
    p.add_argument("--size", default="1200x900", help="picture size WxH in pixels (default 1200x900)")
    p.add_argument("--view", default="iso", choices=["iso", "x", "y", "z", "-x", "-y", "-z"],
                   help="camera direction: iso (default) or looking along an axis")
    p.add_argument("--up", default="z", choices=["z", "y"],
                   help="the body's up axis: z (default) or y (characters from glTF, Maya or X files); a y-up "
                        "body is turned so that it stands")
    p.add_argument("--rest", action="store_true", help="also draw the rest shape as a faint wireframe")
    p.add_argument("--edges", action="store_true", help="draw element edges on the surface")
    p.add_argument("--fibers", action="store_true",
                   help="draw the muscles' fibre directions (at rest) as dark strokes at their cells' centres, "
                        "inside a translucent body (a run with a Muscles section)")
    p.add_argument("--skin", action="store_true",
                   help="draw the skin a voxelized mesh carries (skin_NNNNNN.obj) in flesh colour instead of the mesh")
    p.add_argument("--lbs", action="store_true",
                   help="with a rig: beside each simulated skin, the file's own linear-blend skin of the same step "
                        "(lbs_NNNNNN.obj; implies --skin)")
    p.add_argument("--cut", default=None, choices=["x", "y", "z"],
                   help="cut the body in half by the plane through the middle of the run across this axis and show "
                        "the far half's cut face (inside a crease: where flesh presses on flesh)")
    p.add_argument("--title", default=None, help="a title above the picture")
    p.add_argument("-o", "--output", default=None,
                   help="PNG file (default RESULTS/render_stepNNNNNN.png, or render_strip.png for several steps)")
    return p.parse_args(argv)


def written_steps(results):
    """(step, load, h5 file) of every step the XDMF index lists, in order."""
    xdmf = sorted(glob.glob(os.path.join(results, "*.xdmf")))
    if not xdmf:
        fail(f"no .xdmf index in '{results}' (was the run's HDF5 output turned off?)")
    if len(xdmf) > 1:
        fail(f"several .xdmf files in '{results}': " + ", ".join(os.path.basename(x) for x in xdmf))
    try:
        root = ET.parse(xdmf[0]).getroot()
    except ET.ParseError as e:
        fail(f"{xdmf[0]}: not readable XDMF ({e})")
    steps = []
    for grid in root.iter("Grid"):
        if grid.get("GridType") != "Uniform":
            continue
        load = float(grid.find("Time").get("Value"))
        step = int(grid.get("Name").split()[-1])
        item = grid.find("Geometry/DataItem").text.strip()
        steps.append((step, load, os.path.join(results, item.split(":")[0])))
    if not steps:
        fail(f"{xdmf[0]} lists no steps")
    return xdmf[0], steps


def choose(steps, spec):
    if spec == "last":
        return [steps[-1]]
    if spec == "first":
        return [steps[0]]
    if spec == "all":
        return steps
    if spec.startswith("strip:"):
        try:
            n = int(spec[6:])
        except ValueError:
            fail(f"--steps {spec}: N must be a whole number")
        if n < 1:
            fail("--steps strip:N needs N >= 1")
        idx = sorted(set(int(round(i)) for i in np.linspace(0, len(steps) - 1, min(n, len(steps)))))
        return [steps[i] for i in idx]
    by_number = {s[0]: s for s in steps}
    chosen = []
    for item in spec.split(","):
        try:
            k = int(item)
        except ValueError:
            fail(f"--steps: '{item}' is not a step number (or last, first, all, strip:N)")
        if k not in by_number:
            fail(f"--steps: step {k} was not written; written steps: " + ", ".join(str(s) for s in by_number))
        chosen.append(by_number[k])
    return chosen


def bounds_of_run(steps):
    """Bounding box of the deformed shape over every written step (the fixed camera frames it)."""
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for _, _, f in steps:
        with h5py.File(f, "r") as h:
            x = h["/position"][...]
        lo, hi = np.minimum(lo, x.min(axis=0)), np.maximum(hi, x.max(axis=0))
    return lo, hi


def field_range(chosen, field):
    lo, hi = np.inf, -np.inf
    for _, _, f in chosen:
        with h5py.File(f, "r") as h:
            if "/" + field not in h:
                fail(f"{f} has no field '{field}' (contact_pressure needs a run with a Contact section)")
            v = h["/" + field][...]
        if v.ndim == 2:
            v = np.linalg.norm(v, axis=1)
        lo, hi = min(lo, float(v.min())), max(hi, float(v.max()))
    if field == "J":  # centre on 1 (no volume change) so that loss and gain read alike
        d = max(abs(lo - 1.0), abs(hi - 1.0), 1e-3)
        return 1.0 - d, 1.0 + d
    return (lo, hi) if hi > lo else (lo - 1e-12, hi + 1e-12)


def draw_fibers(pv, view, body, shown, extent):
    """The muscle cells' fibre directions (the "fiber" cell field, zero outside muscles) as strokes."""
    for _, _, f in shown:
        with h5py.File(f, "r") as h:
            if "/fiber" not in h:
                fail(f"{f} has no field 'fiber' (--fibers needs a run with a Muscles section)")
    length = pv.Calculator(Input=body, AttributeType="Cell Data", ResultArrayName="fiber_length", Function="mag(fiber)")
    muscle = pv.Threshold(Input=length, Scalars=["CELLS", "fiber_length"])
    try:  # ParaView >= 5.10
        muscle.LowerThreshold, muscle.UpperThreshold = 0.5, 2.0
    except AttributeError:
        muscle.ThresholdRange = [0.5, 2.0]
    centres = pv.CellCenters(Input=muscle)
    strokes = pv.Glyph(Input=centres, GlyphType="Line")
    strokes.OrientationArray = ["POINTS", "fiber"]
    strokes.ScaleArray = ["POINTS", "No scale array"]
    strokes.ScaleFactor = 0.02 * max(extent)
    strokes.GlyphMode = "All Points"
    g = pv.Show(strokes, view)
    g.ColorArrayName = [None, ""]
    g.AmbientColor = g.DiffuseColor = [0.15, 0.1, 0.1]
    g.LineWidth = 2.0


def main(argv):
    a = parse_args(argv)
    for r in a.results:
        if not os.path.isdir(r):
            fail(f"'{r}' is not a folder")
    try:
        w, h = (int(v) for v in a.size.lower().split("x"))
        assert 16 <= w <= 8192 and 16 <= h <= 8192
    except (ValueError, AssertionError):
        fail(f"--size '{a.size}' must be WxH with each side from 16 to 8192")
    labels = a.labels.split(",") if a.labels else [os.path.basename(os.path.abspath(r)) for r in a.results]
    if len(labels) != len(a.results):
        fail(f"--labels gives {len(labels)} labels for {len(a.results)} folders")
    # Panels: (xdmf, step, load, label), left to right; `shown`: their (step, load, h5 file).
    panels, shown, all_steps = [], [], []
    for r, name in zip(a.results, labels):
        xdmf, steps = written_steps(r)
        chosen = choose(steps, a.steps)
        if len(a.results) > 1 and len(chosen) > 1:
            fail("with several folders --steps must pick one step (last, first or a number)")
        panels += [(xdmf, st, ld, name if len(a.results) > 1 else f"step {st}, load {ld:.3g}") for st, ld, _ in chosen]
        shown += chosen
        all_steps += steps
    if a.lbs:  # each panel twice: the simulated skin, then the plain linear-blend skin of the same step
        a.skin = True
        panels = [(x, st, ld, f"{name}{': ' if name else ''}{kind}", prefix)
                  for x, st, ld, name in panels for kind, prefix in (("simulated", "skin"), ("linear-blend", "lbs"))]
    else:
        panels = [(x, st, ld, name, "skin") for x, st, ld, name in panels]
    lo, hi = bounds_of_run(all_steps)
    data_lo, data_hi = lo.copy(), hi.copy()  # in the data's own axes (for --cut)
    # A y-up body is turned by +90 degrees about x, (x, y, z) -> (x, -z, y), so that it stands on the
    # z-up stage the layout and cameras below assume.
    rotate = [90.0, 0.0, 0.0] if a.up == "y" else [0.0, 0.0, 0.0]
    if a.up == "y":
        lo, hi = np.array([lo[0], -hi[2], lo[1]]), np.array([hi[0], -lo[2], hi[1]])
    if a.range:
        try:
            crange = tuple(float(v) for v in a.range.split(","))
            assert len(crange) == 2 and crange[0] < crange[1]
        except (ValueError, AssertionError):
            fail(f"--range '{a.range}' must be 'lo,hi' with lo < hi")
    else:
        crange = field_range(shown, a.field)

    from paraview import simple as pv  # after the argument checks: importing ParaView takes seconds

    readers = {}
    for xdmf, _, _, _, _ in panels:
        if xdmf not in readers:
            readers[xdmf] = pv.OpenDataFile(xdmf)
            if readers[xdmf] is None:
                fail(f"ParaView cannot open {xdmf}")
    view = pv.CreateView("RenderView")
    view.ViewSize = [w, h]
    view.Background = [1, 1, 1]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    view.OrientationAxesVisibility = 0
    extent = hi - lo
    gap = (0.6 if len(a.results) > 1 else 0.25) * max(extent[0], 1e-12)
    lut = pv.GetColorTransferFunction(a.field)
    lut.ApplyPreset("Cool to Warm", True)
    lut.RescaleTransferFunction(*crange)
    lut.AutomaticRescaleRangeMode = "Never"
    if a.field == "displacement":
        lut.VectorMode = "Magnitude"
    n = len(panels)
    for i, (xdmf, step, load, name, prefix) in enumerate(panels):
        reader = readers[xdmf]
        shift = [i * (extent[0] + gap), 0.0, 0.0]
        if a.skin:  # the carried input surface of this step, as a renderer would show it
            obj = os.path.join(os.path.dirname(xdmf), f"{prefix}_{step:06d}.obj")
            if not os.path.exists(obj):
                fail(f"no {obj}: --skin needs a voxelized run (Mesh/Type voxelize or rig) with 'Surface OBJ' on"
                     + (", --lbs a rig whose Skeleton and Mesh name the same file" if prefix == "lbs" else ""))
            moved = pv.Transform(Input=pv.OpenDataFile(obj))
            moved.Transform.Rotate = rotate
            moved.Transform.Translate = shift
            d = pv.Show(moved, view)
            d.ColorArrayName = [None, ""]
            # Flesh colour for the simulation, a grey-blue for the plain skinning it is compared with.
            d.AmbientColor = d.DiffuseColor = [0.87, 0.66, 0.56] if prefix == "skin" else [0.62, 0.68, 0.78]
            d.Specular = 0.15
        else:
            at = pv.ForceTime(Input=reader, ForcedTime=load, IgnorePipelineTime=1)
            body = at
            if a.cut:  # keep the far half (coordinate above the middle of the run): its cut face looks at us
                axis = "xyz".index(a.cut)
                body = pv.Clip(Input=at)
                body.ClipType = "Plane"
                body.ClipType.Origin = list(0.5 * (data_lo + data_hi))
                body.ClipType.Normal = [1.0 if k == axis else 0.0 for k in range(3)]
                body.Invert = 0
                try:
                    body.Exact = 1
                except AttributeError:
                    pass
            moved = pv.Transform(Input=body)
            moved.Transform.Rotate = rotate
            moved.Transform.Translate = shift
            surface = pv.ExtractSurface(Input=moved)
            d = pv.Show(surface, view)
            d.Representation = "Surface With Edges" if a.edges else "Surface"
            if a.edges:
                d.EdgeColor = [0.2, 0.2, 0.2]
            pv.ColorBy(d, ("POINTS" if a.field in ("displacement", "contact_pressure") else "CELLS", a.field))
            d.LookupTable = lut
            if a.fibers:  # the body translucent: the strokes lie inside it
                d.Opacity = 0.35
                draw_fibers(pv, view, moved, shown, extent)
        if a.rest:
            rest = pv.Transform(Input=pv.ForceTime(Input=reader, ForcedTime=0.0, IgnorePipelineTime=1))
            rest.Transform.Rotate = rotate
            rest.Transform.Translate = shift
            r = pv.Show(pv.ExtractSurface(Input=rest), view)
            r.Representation = "Wireframe"
            r.AmbientColor = r.DiffuseColor = [0.45, 0.45, 0.45]
            r.Opacity = 0.25
            r.ColorArrayName = [None, ""]
        if n > 1:  # a label under each shape, in the scene (so it stays with its shape under any camera)
            label = pv.Transform(Input=pv.a3DText(Text=name))
            # a3DText letters are about 0.75 wide per unit of scale: fit the label under its panel.
            size = min(0.08 * max(extent), 0.9 * (extent[0] + gap) / (0.75 * max(len(name), 1)))
            label.Transform.Scale = [size, size, size]
            label.Transform.Rotate = [90.0, 0.0, 0.0]  # upright, facing -y like the default camera
            label.Transform.Translate = [lo[0] + shift[0], lo[1], lo[2] - 2.0 * size]
            t = pv.Show(label, view)
            t.AmbientColor = t.DiffuseColor = [0.1, 0.1, 0.1]
            t.ColorArrayName = [None, ""]
    bar = pv.GetScalarBar(lut, view)
    bar.Title = {"J": "J = det F", "energy_density": "energy density", "displacement": "|u|",
                 "contact_pressure": "contact pressure", "activation": "muscle activation"}[a.field]
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [0.1, 0.1, 0.1]
    bar.Visibility = 0 if a.skin else 1
    bar.WindowLocation = "Any Location"
    bar.Position = [0.85, 0.2]
    bar.ScalarBarLength = 0.6
    bar.RangeLabelFormat = "%-#.4g"
    bar.LabelFormat = "%-#.4g"
    # Showing and colouring rescale the map to the data: fix it last, the same for every step.
    lut.AutomaticRescaleRangeMode = "Never"
    lut.RescaleTransferFunction(*crange)
    if a.title or n == 1:
        step, load, _ = shown[0]
        text = a.title or f"{labels[0]}: step {step}, load {load:.3g}"
        tt = pv.Show(pv.Text(Text=text), view)
        tt.WindowLocation = "Upper Center"
        tt.FontSize = 16
        tt.Color = [0.1, 0.1, 0.1]

    # One fixed camera for the whole run: it frames the union of every step's shape (and the strip).
    if n > 1:
        lo[2] -= 0.2 * max(extent)  # room for the labels
    box_lo = lo.copy()
    box_hi = hi.copy()
    box_hi[0] += (n - 1) * (extent[0] + gap)
    centre = 0.5 * (box_lo + box_hi)
    radius = 0.5 * float(np.linalg.norm(box_hi - box_lo))
    direction = {"iso": (1.0, -1.6, 0.9), "x": (1, 0, 0), "-x": (-1, 0, 0), "y": (0, 1, 0), "-y": (0, -1, 0),
                 "z": (0, 0, 1), "-z": (0, 0, -1)}[a.view]
    direction = np.array(direction, dtype=float) / np.linalg.norm(direction)
    view.CameraFocalPoint = list(centre)
    view.CameraPosition = list(centre + direction * radius * 4.0)
    view.CameraViewUp = [0, 1, 0] if a.view in ("z", "-z") else [0, 0, 1]
    view.CameraParallelProjection = 1
    # Fit the box of the run (and the strip) as the camera sees it: project its corners on the screen
    # axes; the colour bar keeps the right 18% of the picture.
    up = np.array(view.CameraViewUp, dtype=float)
    right = np.cross(up, direction)
    right /= np.linalg.norm(right)
    up = np.cross(direction, right)
    corners = np.array([[x, y, z] for x in (box_lo[0], box_hi[0]) for y in (box_lo[1], box_hi[1])
                        for z in (box_lo[2], box_hi[2])])
    width, height = np.ptp(corners @ right), np.ptp(corners @ up)
    view.CameraParallelScale = 0.5 * 1.1 * max(height + (0.12 * height if a.title or n == 1 else 0.0),
                                               width / (0.82 * w / h), 1e-12)
    view.CameraFocalPoint = list(centre + right * 0.09 * width / 0.82)
    view.CameraPosition = list(np.array(view.CameraFocalPoint) + direction * radius * 4.0)
    out = a.output or os.path.join(
        a.results[0], f"render_step{shown[0][0]:06d}.png" if n == 1 else
        "render_strip.png" if len(a.results) == 1 else "render_comparison.png")
    pv.SaveScreenshot(out, view, ImageResolution=[w, h], TransparentBackground=0)
    print(out)


if __name__ == "__main__":
    main(sys.argv[1:])
