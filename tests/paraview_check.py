"""Run by pvbatch (tests/test_paraview.sh): open OUTDIR/snapshots.xmf as a
user does and check what ParaView shows, against the snapshots' own counts.

    pvbatch tests/paraview_check.py data OUTDIR EXPECTED.json
    pvbatch tests/paraview_check.py render OUTDIR EXPECTED.json PNG
    pvbatch tests/paraview_check.py probe PNG

EXPECTED.json (written from the HDF5 files with h5py by the shell script):
{"times": [...], "npart": [...], "nmaterial": [...], "cmin": [...], "cmax": [...]}
one entry per snapshot. data checks, at every time step:
  - the reader ParaView picks itself (OpenDataFile: Xdmf3ReaderS in 5.11),
    Xdmf3ReaderT and the legacy XDMF Reader give as many cells as points,
    and as many points as the snapshot has particles (issue 33: the
    Polyvertex topology without connectivity gave 0 cells in the Xdmf3
    readers, so the default views were empty);
  - a Threshold on Kind = 0 (the documented way to hide the walls) keeps the
    material particles only, and its Concentration range is the material's.
render draws the last time step (Points, coloured by Concentration) to PNG
and fails if the picture is blank (fewer than 0.5 % of its pixels differ
from the background). probe draws a plain Sphere the same way: the shell
script runs it when render did not end by itself, to tell a machine whose
OpenGL cannot draw at all (the ParaView of a CI machine once died of a
signal making its first render view) from a view of ours that fails.
Each mode runs in its own pvbatch, so a render that dies cannot hide the
data checks. Prints one line per check; exits 1 on any failure."""
import json
import os
import sys

from paraview.simple import (ColorBy, GetActiveViewOrCreate, OpenDataFile, Render, ResetCamera,
                             SaveScreenshot, Show, Sphere, Threshold, XDMFReader, Xdmf3ReaderS, Xdmf3ReaderT)
from paraview import servermanager

failures = []


def check(ok, what):
    print(("PASS " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def dataset(proxy, t):
    proxy.UpdatePipeline(t)
    d = servermanager.Fetch(proxy)
    while d is not None and d.IsA("vtkMultiBlockDataSet"):  # a collection gives blocks
        d = d.GetBlock(0)
    return d


def data_checks(xmf, exp):
    readers = {
        "default (OpenDataFile)": OpenDataFile(xmf),
        "Xdmf3ReaderT": Xdmf3ReaderT(FileName=[xmf]),
        "XDMF Reader (legacy)": XDMFReader(FileNames=[xmf]),
    }
    check(type(readers["default (OpenDataFile)"]).__name__ in ("Xdmf3ReaderS", "Xdmf3ReaderT", "XDMFReader"),
          "ParaView picks an XDMF reader for snapshots.xmf (%s)" % type(readers["default (OpenDataFile)"]).__name__)
    readers["Xdmf3ReaderS"] = Xdmf3ReaderS(FileName=[xmf])
    ntimes = len(exp["times"])
    for name, r in readers.items():
        ts = list(r.TimestepValues) if r.TimestepValues else [0.0]
        check(len(ts) == ntimes, "%s: %d time steps (snapshots: %d)" % (name, len(ts), ntimes))
        for k, t in enumerate(ts[:ntimes]):
            d = dataset(r, t)
            n_pts, n_cells = d.GetNumberOfPoints(), d.GetNumberOfCells()
            check(n_pts == exp["npart"][k] and n_cells == n_pts,
                  "%s, t = %g: %d points, %d cells, %d particles" % (name, t, n_pts, n_cells, exp["npart"][k]))

    # the walls hidden: Threshold on Kind between 0 and 0 (material)
    r = readers["default (OpenDataFile)"]
    thr = Threshold(Input=r)
    thr.Scalars = ["POINTS", "Kind"]
    thr.LowerThreshold = 0
    thr.UpperThreshold = 0
    for k, t in enumerate(list(r.TimestepValues)[:ntimes]):
        d = dataset(thr, t)
        c = d.GetPointData().GetArray("Concentration")
        lo, hi = c.GetRange() if c is not None else (float("nan"), float("nan"))
        check(d.GetNumberOfPoints() == exp["nmaterial"][k] and abs(lo - exp["cmin"][k]) < 1e-12
              and abs(hi - exp["cmax"][k]) < 1e-12,
              "Threshold Kind = 0, t = %g: %d points (material %d), Concentration [%g, %g] (material [%g, %g])"
              % (t, d.GetNumberOfPoints(), exp["nmaterial"][k], lo, hi, exp["cmin"][k], exp["cmax"][k]))


def draw(source, png, time=None, colour=None, representation="Points"):
    """Show source in a 400 x 300 render view and save it as png."""
    view = GetActiveViewOrCreate("RenderView")
    view.ViewSize = [400, 300]
    if time is not None:
        view.ViewTime = time
    disp = Show(source, view)
    disp.SetRepresentationType(representation)
    disp.PointSize = 3
    if colour is not None:
        ColorBy(disp, ("POINTS", colour))
    ResetCamera(view)
    Render(view)
    SaveScreenshot(png, view, ImageResolution=[400, 300], TransparentBackground=0)


def not_blank(png):
    from vtkmodules.vtkIOImage import vtkPNGReader

    img = vtkPNGReader()
    img.SetFileName(png)
    img.Update()
    im = img.GetOutput()
    nx, ny, _ = im.GetDimensions()
    sc = im.GetPointData().GetScalars()
    nc = sc.GetNumberOfComponents()
    bg = [sc.GetComponent(0, c) for c in range(nc)]
    differ = sum(1 for i in range(nx * ny) if any(abs(sc.GetComponent(i, c) - bg[c]) > 8 for c in range(min(nc, 3))))
    check(differ > 0.005 * nx * ny, "the rendered picture %s is not blank: %d of %d pixels differ from the background"
          % (png, differ, nx * ny))


mode = sys.argv[1] if len(sys.argv) > 1 else ""
if mode in ("data", "render") and len(sys.argv) == 4 + (mode == "render"):
    xmf = sys.argv[2] + "/snapshots.xmf"
    exp = json.load(open(sys.argv[3]))
    if mode == "data":
        data_checks(xmf, exp)
    else:  # the last time step, as the default Points view shows it
        r = OpenDataFile(xmf)
        draw(r, sys.argv[4], time=list(r.TimestepValues)[-1], colour="Concentration")
        not_blank(sys.argv[4])
elif mode == "probe" and len(sys.argv) == 3:
    draw(Sphere(), sys.argv[2], representation="Surface")
    not_blank(sys.argv[2])
else:
    print(__doc__)
    os._exit(2)
print("%d check(s) failed" % len(failures) if failures else "all ParaView checks passed (%s)" % mode)
sys.stdout.flush()
os._exit(1 if failures else 0)  # not sys.exit: pvbatch's teardown under xvfb can fail (GLXBadContext), exit 1
