"""Opens a bfemp run's bfemp.xdmf in ParaView and checks it against bfemp.h5.

Run by pvpython (ParaView 5.11):
    pvpython tests/paraview/check_xdmf.py RUN_DIR [--grids LAYOUT] [--screenshot FILE.png] [--strict]
Plain python3 with h5py prints the HDF5 summary this script compares against
(used by pvpython when its own Python has no h5py):
    python3 tests/paraview/check_xdmf.py RUN_DIR --h5-summary

--grids names the layout the run must have written (the grids of each frame):
  fem,particles  (default) an implicit run: per frame a spatial collection of
                 the grids fem and particles;
  particles      an explicit run (Solver: explicit): per frame one Uniform grid
                 `particles`, no fem grid, no spatial collection.

Checks, for each of ParaView's Xdmf3 readers (Xdmf3ReaderT: one named block
per grid; Xdmf3ReaderS: the grids as pieces of one dataset; with a single grid
per frame both give that grid's dataset, not a multiblock):
- the number of time steps equals the number of /frame_* groups of bfemp.h5,
  and each time value equals the frame's `time` attribute;
- at every time step the layout's grids are there, in its order (Xdmf3ReaderT:
  named `fem` / `particles`, the reader appends `[k]` after the first step);
- grid fem: its points equal /frame_k/positions (z = 0 in 2D), its cells are
  triangles (2D) or tetrahedra (3D) with the connectivity of /mesh/cells;
- grid particles: its points equal /frame_k/particle_positions (z = 0 in 2D);
- every array of every grid (point and cell data: velocity, von_mises, J,
  body, contact_force; in the explicit layout also stress (9 components),
  pressure and material_class; and any other the XDMF names) has the number of
  tuples and components of its HDF5 dataset, an integer type where the
  dataset is integer (float where it is float), and the same per-component
  minimum, maximum and sum; in the XDMF its AttributeType fits its components
  (Scalar 1, Vector 2 or 3, Tensor6 6, Tensor 9) and its NumberType the
  dataset's type; the documented arrays must be there (in the reader's array
  lists and in the data), and every dataset of every frame must be reachable
  from the XDMF (nothing written is invisible);
- --screenshot: the last time step rendered into a PNG that is checked not to
  be blank: fem,particles: FEM surface with edges and the particles as points,
  both coloured by von_mises; particles: the particles as points coloured by
  material_class (the explicit b1 run's von_mises is round-off noise at its
  first steps; material_class tells the two bodies apart).
The particles grid must have one cell per particle, cell i the vertex of
particle i (bfemp writes the Polyvertex connectivity /mesh/particle_vertices;
without it the Xdmf3 readers give no cells and the Surface and Points
representations draw nothing).
Exit status: 0 all checks pass, 1 a check failed, 2 usage or missing files.
"""
import json
import math
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

FEM, PARTICLES = "fem", "particles"
# Per layout (--grids): the grids of each frame in their order, and the arrays
# bfemp documents for each grid (README, Output; src/app/explicit_output.hpp);
# contact_force only in contact scenes of the implicit run.
LAYOUTS = {
    "fem,particles": {
        FEM: {("point", "velocity"), ("cell", "von_mises"), ("cell", "J")},
        PARTICLES: {("point", "velocity"), ("point", "von_mises"), ("point", "J"), ("point", "body")},
    },
    "particles": {
        PARTICLES: {("point", "velocity"), ("point", "stress"), ("point", "von_mises"), ("point", "J"),
                    ("point", "body"), ("point", "material_class")},
    },
}
CONTACT_ARRAY = (PARTICLES, "point", "contact_force")
# The dataset each XDMF attribute must read, per layout and grid (a swap of two
# same-shaped datasets, e.g. von_mises and pressure, passes every other check).
DATASETS = {
    "particles": {
        PARTICLES: {("point", "velocity"): "particle_velocities", ("point", "stress"): "particle_stress",
                    ("point", "von_mises"): "particle_von_mises", ("point", "pressure"): "particle_pressure",
                    ("point", "J"): "particle_J", ("point", "body"): "particle_body",
                    ("point", "material_class"): "particle_material_class"},
    },
}
# XDMF AttributeType by number of components (src/io/xdmf_writer.cpp).
ATTRIBUTE_TYPES = {1: "Scalar", 2: "Vector", 3: "Vector", 6: "Tensor6", 9: "Tensor"}


# ---------------------------------------------------------------- HDF5 side
def h5_summary(run_dir):
    """Shapes, time attributes and per-component min/max/sum of every dataset."""
    import h5py
    import numpy as np

    out = {"frames": [], "cells": None}
    with h5py.File(os.path.join(run_dir, "bfemp.h5"), "r") as f:
        if "mesh" in f and "cells" in f["mesh"]:
            out["cells"] = np.asarray(f["mesh/cells"]).astype(np.int64).tolist()
        for name in sorted(k for k in f if k.startswith("frame_")):
            g = f[name]
            fr = {"name": name, "time": float(g.attrs["time"]), "step": int(g.attrs["step"]), "datasets": {}}
            for ds in g:
                a = np.asarray(g[ds])
                a2 = a.reshape(a.shape[0], -1).astype(np.float64) if a.ndim else a.reshape(1, 1)
                fr["datasets"][ds] = {
                    "shape": list(a.shape),
                    "kind": "int" if a.dtype.kind in "iu" else "float",
                    "min": a2.min(axis=0).tolist() if a2.shape[0] else [],
                    "max": a2.max(axis=0).tolist() if a2.shape[0] else [],
                    "sum": a2.sum(axis=0).tolist(),
                    "values": a2.tolist() if ds.endswith("positions") else None,
                }
            out["frames"].append(fr)
    return out


def load_h5_summary(run_dir):
    if not os.environ.get("BFEMP_CHECK_NO_H5PY"):  # set it to test the fallback
        try:
            import h5py  # noqa: F401
            return h5_summary(run_dir)
        except ImportError:
            pass
    py = os.environ.get("BFEMP_PYTHON3", "/usr/bin/python3")
    print(f"check_xdmf: no h5py in {sys.executable}; reading bfemp.h5 with {py}")
    res = subprocess.run([py, os.path.abspath(__file__), run_dir, "--h5-summary"],
                         capture_output=True, text=True)
    if res.returncode != 0:
        raise SystemExit(f"check_xdmf: {py} could not read bfemp.h5 (python3-h5py missing?):\n{res.stderr}")
    return json.loads(res.stdout)


# ---------------------------------------------------------------- XDMF side
def xdmf_frames(path):
    """Per temporal step: {grid name: {"geometry": ds, "topology": ..., "attrs": {(center, name): ds}}}.

    A step is either a spatial collection of Uniform grids (implicit run) or
    one Uniform grid itself (explicit run); "kind" says which.
    """
    root = ET.parse(path).getroot()
    series = root.find("Domain/Grid")
    if series is None or series.get("CollectionType") != "Temporal":
        raise SystemExit(f"{path}: no temporal collection under Domain")
    frames = []
    for step in series.findall("Grid"):
        grids = {}
        paths = []
        children = step.findall("Grid")
        if children:
            kind = f"{step.get('GridType')}/{step.get('CollectionType')}"
        else:
            kind = step.get("GridType", "Uniform")
            children = [step]
        for g in children:
            def ds_of(elem):
                item = elem.find("DataItem")
                if item is None:
                    return None
                path = item.text.strip().split(":", 1)[-1]  # bfemp.h5:/frame_NNNNNN/name
                paths.append(path)
                return path.rsplit("/", 1)[-1]

            def meta_of(a):
                item = a.find("DataItem")
                return {"type": a.get("AttributeType"),
                        "number": item.get("NumberType") if item is not None else None,
                        "dims": [int(x) for x in item.get("Dimensions", "").split()] if item is not None else None}
            topo = g.find("Topology")
            center = {a: "point" if a.get("Center") == "Node" else "cell" for a in g.findall("Attribute")}
            grids[g.get("Name")] = {
                "topology": (topo.get("TopologyType"), int(topo.get("NumberOfElements")),
                             int(topo.get("NodesPerElement", "0")), topo.find("DataItem") is not None),
                "geometry": ds_of(g.find("Geometry")),
                "attrs": {(center[a], a.get("Name")): ds_of(a) for a in g.findall("Attribute")},
                "meta": {(center[a], a.get("Name")): meta_of(a) for a in g.findall("Attribute")},
                "order": [x.get("Name") for x in children],
            }
        time = step.find("Time")
        frames.append({"time": float(time.get("Value")) if time is not None else None, "grids": grids,
                       "paths": paths, "kind": kind})
    return frames


# ------------------------------------------------------------------ checks
class Checker:
    def __init__(self):
        self.failures = []
        self.known = []
        self.checks = 0

    def ok(self, cond, msg):
        self.checks += 1
        if not cond:
            self.failures.append(msg)
            print("FAIL:", msg)
        return cond


def close(a, b, scale):
    return abs(a - b) <= 1e-12 * max(1.0, abs(scale)) + 1e-300


def leaves(data):
    """Leaf datasets in order, with their block names (None for pieces).

    A single grid per frame comes back as that dataset itself (no multiblock):
    one leaf, named None.
    """
    if not data.IsA("vtkCompositeDataSet"):
        return [(None, data)]
    out = []
    it = data.NewIterator()
    it.InitTraversal()
    while not it.IsDoneWithTraversal():
        md = it.GetCurrentMetaData() if it.HasCurrentMetaData() else None
        name = md.Get(data.NAME()) if md is not None and md.Has(data.NAME()) else None
        out.append((name, it.GetCurrentDataObject()))
        it.GoToNextItem()
    return out


def array_stats(arr):
    from vtkmodules.util.numpy_support import vtk_to_numpy

    a = vtk_to_numpy(arr).astype("float64")
    a = a.reshape(a.shape[0], -1)
    return a


def is_integer_array(arr):
    from vtkmodules.util.numpy_support import vtk_to_numpy

    return vtk_to_numpy(arr).dtype.kind in "iu"


def check_reader(ck, reader_name, run_dir, h5, xf, dim, layout):
    from paraview import servermanager as sm
    from paraview import simple as pv
    from vtkmodules.util.numpy_support import vtk_to_numpy

    required = LAYOUTS[layout]
    grids = tuple(required)
    fn = os.path.join(run_dir, "bfemp.xdmf")
    reader = getattr(pv, reader_name)(FileName=[fn])
    times = list(reader.TimestepValues or [])
    frames = h5["frames"]
    tag = reader_name
    ck.ok(len(times) == len(frames), f"{tag}: {len(times)} time steps, bfemp.h5 has {len(frames)} /frame_* groups")
    for k, (t, fr) in enumerate(zip(times, frames)):
        ck.ok(close(t, fr["time"], fr["time"]), f"{tag}: time step {k} is t = {t}, {fr['name']} has time {fr['time']}")
    # The reader's array lists (what the GUI offers) hold every documented
    # array: its array selection (the Properties panel before Apply) and its
    # data information (the colouring menu). The data information of a reader
    # whose output is one dataset (a single grid per frame) is empty until the
    # pipeline has run, so it is taken after the first time step's update.
    selection = {("point", n) for n in (reader.PointArrays or [])} | {("cell", n) for n in (reader.CellArrays or [])}
    if times:
        reader.UpdatePipeline(times[0])
    offered = {("point", n) for n in reader.PointData.keys()} | {("cell", n) for n in reader.CellData.keys()}
    for grid, req in required.items():
        for assoc, name in sorted(req):
            ck.ok((assoc, name) in selection, f"{tag}: the reader's {assoc} array selection has no '{name}' (grid {grid})")
            ck.ok((assoc, name) in offered, f"{tag}: the reader offers no {assoc} array '{name}' (grid {grid})")
    cells_ref = h5["cells"]
    for k, (t, fr) in enumerate(zip(times, frames)):
        reader.UpdatePipeline(t)
        data = sm.Fetch(reader)
        blocks = leaves(data)
        where = f"{tag}, time step {k} (t = {t:g}, {fr['name']})"
        if not ck.ok(len(blocks) == len(grids),
                     f"{where}: {len(blocks)} datasets, expected {len(grids)} ({', '.join(grids)})"):
            continue
        xgrids = xf[k]["grids"] if k < len(xf) else {}
        for (bname, ds), grid in zip(blocks, grids):
            gw = f"{where}, grid {grid}"
            if reader_name == "Xdmf3ReaderT" and data.IsA("vtkCompositeDataSet"):
                ck.ok(bname in (grid, f"{grid}[{k}]"), f"{gw}: block named '{bname}'")
            xg = xgrids.get(grid)
            if not ck.ok(xg is not None, f"{gw}: not in the XDMF"):
                continue
            pre = "particle_" if grid == PARTICLES else ""
            dsets = fr["datasets"]
            # Geometry.
            gname = xg["geometry"]
            ck.ok(gname == pre + "positions", f"{gw}: geometry reads '{gname}', expected '{pre}positions'")
            ref = dsets.get(pre + "positions")
            if not ck.ok(ref is not None, f"{gw}: {fr['name']} has no dataset {pre}positions"):
                continue
            npts = ref["shape"][0]
            ck.ok(ds.GetNumberOfPoints() == npts, f"{gw}: {ds.GetNumberOfPoints()} points, HDF5 {pre}positions has {npts}")
            if ds.GetNumberOfPoints() == npts and npts:
                p = vtk_to_numpy(ds.GetPoints().GetData())
                vals = ref["values"]
                err = max(abs(p[i, c] - vals[i][c]) for i in range(npts) for c in range(dim))
                zerr = max(abs(p[i, c]) for i in range(npts) for c in range(dim, 3)) if dim < 3 else 0.0
                ck.ok(err == 0.0 and zerr == 0.0, f"{gw}: points differ from {pre}positions by {err:g} (z off by {zerr:g})")
            # Topology.
            ncells = ds.GetNumberOfCells()
            if grid == FEM:
                nc = len(cells_ref) if cells_ref is not None else -1
                ck.ok(ncells == nc, f"{gw}: {ncells} cells, /mesh/cells has {nc}")
                want = 5 if dim == 2 else 10  # VTK_TRIANGLE, VTK_TETRA
                types = {ds.GetCellType(i) for i in range(ncells)}
                ck.ok(types == {want}, f"{gw}: cell types {sorted(types)}, expected {{{want}}}")
                if ncells == nc and nc > 0:
                    conn = vtk_to_numpy(ds.GetCells().GetConnectivityArray()).reshape(nc, -1)
                    ck.ok(conn.tolist() == cells_ref, f"{gw}: connectivity differs from /mesh/cells")
            else:
                if ck.ok(ncells == npts, f"grid particles has {ncells} cells for {npts} points in {reader_name}: "
                         f"Surface/Points representations would draw no particles") and npts:
                    types = {ds.GetCellType(i) for i in range(ncells)}
                    ck.ok(types <= {1, 2}, f"{gw}: cell types {sorted(types)}, expected vertices (VTK_VERTEX 1 / VTK_POLY_VERTEX 2)")
                    conn = vtk_to_numpy(ds.GetCells().GetConnectivityArray())
                    ck.ok(conn.tolist() == list(range(npts)),
                          f"{gw}: cell i is not the vertex of particle i (/mesh/particle_vertices)")
            # Arrays: every XDMF attribute against its HDF5 dataset.
            fds = {"point": ds.GetPointData(), "cell": ds.GetCellData()}
            seen = {(a, n) for a in fds for n in (fds[a].GetArrayName(i) for i in range(fds[a].GetNumberOfArrays()))}
            req = set(required[grid])
            if grid == CONTACT_ARRAY[0] and "particle_contact_force" in dsets:
                req.add(CONTACT_ARRAY[1:])
            for assoc, name in sorted(req):
                ck.ok((assoc, name) in seen, f"{gw}: no {assoc} array '{name}' (has {sorted(seen)})")
            for (assoc, name), dname in sorted(xg["attrs"].items()):
                aw = f"{gw}, {assoc} array '{name}' ({dname})"
                arr = fds[assoc].GetArray(name)
                ref = dsets.get(dname)
                if not ck.ok(ref is not None, f"{aw}: no such dataset in {fr['name']}"):
                    continue
                if not ck.ok(arr is not None, f"{aw}: ParaView has no such array"):
                    continue
                shape = ref["shape"]
                ncomp = 1 if len(shape) == 1 else int(math.prod(shape[1:]))
                ck.ok(arr.GetNumberOfTuples() == shape[0],
                      f"{aw}: {arr.GetNumberOfTuples()} tuples, HDF5 has {shape[0]}")
                ck.ok(arr.GetNumberOfComponents() == ncomp,
                      f"{aw}: {arr.GetNumberOfComponents()} components, HDF5 has {ncomp}")
                kind = ref.get("kind", "float")
                ck.ok(is_integer_array(arr) == (kind == "int"),
                      f"{aw}: ParaView's array is {arr.GetClassName()}, the HDF5 dataset is {kind}")
                meta = xg["meta"][(assoc, name)]
                ck.ok(meta["type"] == ATTRIBUTE_TYPES.get(ncomp, "Matrix"),
                      f"{aw}: XDMF AttributeType {meta['type']} for {ncomp} components")
                ck.ok(meta["number"] == ("Int" if kind == "int" else "Float"),
                      f"{aw}: XDMF NumberType {meta['number']}, the HDF5 dataset is {kind}")
                ck.ok(meta["dims"] == shape, f"{aw}: XDMF Dimensions {meta['dims']}, HDF5 shape {shape}")
                want_n = npts if assoc == "point" else ncells if grid == FEM else shape[0]
                ck.ok(shape[0] == want_n, f"{aw}: HDF5 length {shape[0]}, the grid has {want_n} {assoc}s")
                if arr.GetNumberOfTuples() == shape[0] and arr.GetNumberOfComponents() == ncomp and shape[0]:
                    a = array_stats(arr)
                    for c in range(ncomp):
                        mn, mx, sm_ = float(a[:, c].min()), float(a[:, c].max()), float(a[:, c].sum())
                        scale = max(abs(ref["min"][c]), abs(ref["max"][c])) * shape[0]
                        ck.ok(mn == ref["min"][c] and mx == ref["max"][c] and close(sm_, ref["sum"][c], scale),
                              f"{aw}: component {c}: ParaView min/max/sum {mn:g}/{mx:g}/{sm_:g}, "
                              f"HDF5 {ref['min'][c]:g}/{ref['max'][c]:g}/{ref['sum'][c]:g}")
    return times


def check_xdmf_covers_h5(ck, h5, xf, layout):
    grids = list(LAYOUTS[layout])
    frames = h5["frames"]
    ck.ok(len(xf) == len(frames), f"XDMF lists {len(xf)} frames, bfemp.h5 has {len(frames)}")
    for k, (x, fr) in enumerate(zip(xf, frames)):
        order = next(iter(x["grids"].values()))["order"] if x["grids"] else []
        ck.ok(set(x["grids"]) == set(grids) and order == grids,
              f"XDMF frame {k}: grids {order}, expected {', '.join(grids)}")
        want_kind = "Uniform" if len(grids) == 1 else "Collection/Spatial"
        ck.ok(x["kind"] == want_kind, f"XDMF frame {k}: a {x['kind']} grid, expected {want_kind}")
        for grid, names in DATASETS.get(layout, {}).items():
            attrs = x["grids"].get(grid, {}).get("attrs", {})
            for key, dname in sorted(names.items()):
                ck.ok(key not in attrs or attrs[key] == dname,
                      f"XDMF frame {k}, grid {grid}: {key[0]} array '{key[1]}' reads {attrs.get(key)}, expected {dname}")
        used = set()
        for g in x["grids"].values():
            used.add(g["geometry"])
            used.update(g["attrs"].values())
        stray = sorted(p for p in x["paths"] if not p.startswith(f"/{fr['name']}/") and p not in ("/mesh/cells", "/mesh/particle_vertices"))
        ck.ok(not stray, f"XDMF frame {k}: reads datasets outside /{fr['name']}: {stray}")
        missing = sorted(set(fr["datasets"]) - used)
        ck.ok(not missing, f"XDMF frame {k}: datasets of {fr['name']} no grid reads: {missing}")
        ck.ok(x["time"] is not None and close(x["time"], fr["time"], fr["time"]),
              f"XDMF frame {k}: Time {x['time']}, {fr['name']} time {fr['time']}")


def show_particles(pv, src, view, assoc_name):
    """Particles as Point Gaussian discs, a third of the mean spacing in radius."""
    d = pv.Show(src, view)
    d.SetRepresentationType("Point Gaussian")
    pv.ColorBy(d, assoc_name)
    b = src.GetDataInformation().GetBounds()
    n = max(1, src.GetDataInformation().GetNumberOfPoints())
    area = max((b[1] - b[0]) * (b[3] - b[2]), 1e-30)
    d.GaussianRadius = 0.33 * math.sqrt(area / n)
    d.ShaderPreset = "Plain circle"
    return d


def screenshot(ck, run_dir, png, layout="fem,particles"):
    from paraview import simple as pv

    reader = pv.Xdmf3ReaderT(FileName=[os.path.join(run_dir, "bfemp.xdmf")])
    t = reader.TimestepValues[-1]
    view = pv.CreateView("RenderView")
    view.ViewSize = [1200, 600]
    view.ViewTime = t
    view.OrientationAxesVisibility = 0
    view.Background = [1.0, 1.0, 1.0]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    if FEM not in LAYOUTS[layout]:
        screenshot_particles(pv, reader, view, t)
    else:
        screenshot_fem_particles(pv, reader, view, t)
    save_and_check(ck, pv, view, png)


def screenshot_particles(pv, reader, view, t):
    """Explicit run: the one particle grid, coloured by material_class."""
    pv.UpdatePipeline(t, reader)
    lut = pv.GetColorTransferFunction("material_class")
    lut.ApplyPreset("Viridis (matplotlib)", True)
    d_par = show_particles(pv, reader, view, ("POINTS", "material_class"))
    ai = reader.GetDataInformation().GetPointDataInformation().GetArrayInformation("material_class")
    if ai is not None:
        lo, hi = ai.GetComponentRange(0)
        lut.RescaleTransferFunction(lo, hi if hi > lo else lo + 1.0)
    bar = pv.GetScalarBar(lut, view)
    bar.Title = "material class"
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [0.1, 0.1, 0.1]
    bar.DrawTickLabels = 0  # integer classes: only the range, as integers
    bar.RangeLabelFormat = "%.0f"
    d_par.SetScalarBarVisibility(view, True)
    text = pv.Text(Text=f"bfemp (explicit): particles (points) by material class, t = {t:.4g} s")
    td = pv.Show(text, view)
    td.Color = [0.1, 0.1, 0.1]
    td.WindowLocation = "Upper Left Corner"
    view.InteractionMode = "2D"
    pv.ResetCamera(view)
    # Bodies stacked in y fill the wide view's height: a margin, no zoom.
    view.CameraParallelScale *= 1.1


def screenshot_fem_particles(pv, reader, view, t):
    """Implicit run: FEM surface with edges and particles, both by von_mises."""
    # Blocks by position: the reader names them fem, particles at the first
    # step and fem[k], particles[k] at step k.
    fem = pv.ExtractBlock(Input=reader, Selectors=["/Root/*[1]"])
    par = pv.ExtractBlock(Input=reader, Selectors=["/Root/*[2]"])
    lut = pv.GetColorTransferFunction("von_mises")
    lut.ApplyPreset("Viridis (matplotlib)", True)
    d_fem = pv.Show(fem, view)
    d_fem.SetRepresentationType("Surface With Edges")
    pv.ColorBy(d_fem, ("CELLS", "von_mises"))
    d_fem.EdgeColor = [0.2, 0.2, 0.2]
    show_particles(pv, par, view, ("POINTS", "von_mises"))
    lo, hi = [], []
    for src, assoc in ((fem, "cell"), (par, "point")):
        info = src.GetDataInformation()
        ai = (info.GetCellDataInformation() if assoc == "cell" else info.GetPointDataInformation()).GetArrayInformation("von_mises")
        if ai is not None:
            r = ai.GetComponentRange(0)
            lo.append(r[0])
            hi.append(r[1])
    if lo:
        lut.RescaleTransferFunction(min(lo), max(hi) if max(hi) > min(lo) else min(lo) + 1.0)
    bar = pv.GetScalarBar(lut, view)
    bar.Title = "von Mises (Pa)"
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [0.1, 0.1, 0.1]
    d_fem.SetScalarBarVisibility(view, True)
    text = pv.Text(Text=f"bfemp: fem (surface) and particles (points), t = {t:.4g} s")
    td = pv.Show(text, view)
    td.Color = [0.1, 0.1, 0.1]
    td.WindowLocation = "Upper Left Corner"
    view.InteractionMode = "2D"
    pv.ResetCamera(view)
    view.CameraParallelScale *= 0.8


def save_and_check(ck, pv, view, png):
    pv.Render(view)
    pv.SaveScreenshot(png, view, ImageResolution=[1200, 600])
    ok = ck.ok(os.path.isfile(png) and os.path.getsize(png) > 0, f"screenshot {png} not written")
    if ok:
        from vtkmodules.vtkIOImage import vtkPNGReader
        from vtkmodules.util.numpy_support import vtk_to_numpy

        r = vtkPNGReader()
        r.SetFileName(png)
        r.Update()
        img = vtk_to_numpy(r.GetOutput().GetPointData().GetScalars())[:, :3].astype(int)
        nonwhite = float((img.sum(axis=1) < 3 * 250).mean())
        colours = len({tuple(c) for c in img[:: max(1, len(img) // 20000)]})
        ck.ok(nonwhite > 0.02 and colours > 20,
              f"screenshot {png} looks blank ({100 * nonwhite:.1f}% non-background pixels, {colours} colours)")
        print(f"check_xdmf: screenshot {png} ({100 * nonwhite:.1f}% of pixels drawn, {colours} colours sampled)")


def main(argv):
    args = [a for a in argv if not a.startswith("--")]
    flags = [a for a in argv if a.startswith("--")]
    values = {}
    for opt in ("--screenshot", "--grids"):
        if opt in argv:
            i = argv.index(opt)
            if i + 1 >= len(argv) or argv[i + 1].startswith("--"):
                print(f"check_xdmf: {opt} needs a value", file=sys.stderr)
                return 2
            values[opt] = argv[i + 1]
            args.remove(argv[i + 1])
    png = values.get("--screenshot")
    layout = values.get("--grids", "fem,particles")
    if layout not in LAYOUTS:
        print(f"check_xdmf: --grids {layout}: expected one of {', '.join(LAYOUTS)}", file=sys.stderr)
        return 2
    if len(args) != 1 or any(f not in ("--screenshot", "--grids", "--strict", "--h5-summary") for f in flags):
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    run_dir = args[0]
    for f in ("bfemp.xdmf", "bfemp.h5"):
        if not os.path.isfile(os.path.join(run_dir, f)):
            print(f"check_xdmf: {os.path.join(run_dir, f)} missing", file=sys.stderr)
            return 2
    if "--h5-summary" in flags:
        json.dump(h5_summary(run_dir), sys.stdout)
        return 0

    h5 = load_h5_summary(run_dir)
    xf = xdmf_frames(os.path.join(run_dir, "bfemp.xdmf"))
    # The dimension from the first grid's positions (fem: positions,
    # particles: particle_positions).
    pos = ("" if next(iter(LAYOUTS[layout])) == FEM else "particle_") + "positions"
    if h5["frames"] and pos not in h5["frames"][0]["datasets"]:
        print(f"check_xdmf: {h5['frames'][0]['name']} has no dataset {pos}: not a '{layout}' run "
              f"(has {sorted(h5['frames'][0]['datasets'])})", file=sys.stderr)
        return 1
    dim = h5["frames"][0]["datasets"][pos]["shape"][1] if h5["frames"] else 2
    print(f"check_xdmf: layout {layout} (grids per frame: {', '.join(LAYOUTS[layout])}), dimension {dim}")
    ck = Checker()
    ck.ok(len(h5["frames"]) >= 2, f"bfemp.h5 has {len(h5['frames'])} frames; the check wants a run with several")
    check_xdmf_covers_h5(ck, h5, xf, layout)
    for reader in ("Xdmf3ReaderT", "Xdmf3ReaderS"):
        times = check_reader(ck, reader, run_dir, h5, xf, dim, layout)
        print(f"check_xdmf: {reader}: {len(times)} time steps checked")
    if png:
        screenshot(ck, run_dir, png, layout)
    for k in ck.known:
        print("KNOWN ISSUE:", k)
    if "--strict" in flags and ck.known:
        ck.failures.extend(ck.known)
    fr = h5["frames"]
    print(f"check_xdmf: {ck.checks} checks over {len(fr)} frames, {len(ck.failures)} failed"
          + (f", {len(ck.known)} known issue(s)" if ck.known else ""))
    return 1 if ck.failures else 0


if __name__ == "__main__":
    rc = main(sys.argv[1:])
    sys.stdout.flush()
    sys.stderr.flush()
    # Leave without ParaView's teardown: under Xvfb its render window's final
    # glXMakeCurrent fails (GLXBadContext) and Xlib's handler exits with 1.
    os._exit(rc)
