"""ParaView's pipeline on weaver's exports, not only its reader: VTK (what
ParaView runs) reads the vtu and the pvtu of a graded basin mesh, cuts them
with a plane that lies on no element boundary, colours the cut by vs and
renders it offscreen (under xvfb-run) to a PNG.  The picture must not be
blank, and the cut must hold exactly the elements `weaver query range`
finds on that plane.
usage: check_render.py WEAVER WORK_DIR"""
import csv
import io
import os
import shutil
import subprocess
import sys

SKIP = 77
weaver_bin, work = sys.argv[1:3]
inside = len(sys.argv) > 3 and sys.argv[3] == "--inside-xvfb"


def fail(message):
    sys.exit("check_render: " + message)


def need(what, ok):
    if ok:
        return
    if os.environ.get("WEAVER_REQUIRE_TOOLS"):
        fail(f"{what} is not installed (WEAVER_REQUIRE_TOOLS is set)")
    print(f"check_render: {what} is not installed: skipped")
    sys.exit(SKIP)


# VTK needs an X display to render: a virtual one, started for this run.
if not inside:
    need("xvfb-run (Debian: xvfb)", shutil.which("xvfb-run") is not None)
    r = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1024x768x24", sys.executable,
                        __file__, weaver_bin, work, "--inside-xvfb"])
    sys.exit(r.returncode)

try:
    import numpy as np
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
except ImportError as e:
    need(f"VTK's and numpy's Python modules ({e})", False)


def run(*args):
    r = subprocess.run([weaver_bin, *args], capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"weaver {' '.join(args)}: {r.stderr}")
    return r.stdout


shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
db = os.path.join(work, "basin.db")
run("mesh", db, "--model", "basin", "--freq", "0.1", "--quiet")
vtu, pvtu = os.path.join(work, "basin.vtu"), os.path.join(work, "basin.pvtu")
run("export", db, "--format", "vtu", "--units", "ticks", "--out", vtu)
run("export", db, "--format", "pvtu", "--parts", "3", "--units", "ticks", "--out", pvtu)

# The plane z = T + 1/2 ticks, T odd: element corners and edges are whole
# even ticks (an element of the finest level here is thousands wide), so no boundary lies on it, and the elements it cuts are those
# whose closed boxes hold the tick plane z = T, which range queries answer.
levels = run("query", db, "range", "0", "0", "0", "1048575", "1048575", "1048575", "--list",
             "--format", "csv")
rows = list(csv.DictReader(io.StringIO(levels)))
finest = max(rows, key=lambda r: int(r["level"]))
T = int(finest["z"]) + 1  # through the finest elements, where the grading is
listed = run("query", db, "range", "0", "0", str(T), "1048575", "1048575", str(T), "--list",
             "--format", "csv")
want = {int(r["element"]) for r in csv.DictReader(io.StringIO(listed))}
levels_cut = {int(r["level"]) for r in csv.DictReader(io.StringIO(listed))}
if len(want) < 100 or len(levels_cut) < 2:
    fail(f"the plane z = {T} cuts {len(want)} elements of levels {levels_cut}: not a graded cut")


def cut_of(reader):
    plane = vtk.vtkPlane()
    plane.SetOrigin(0, 0, T + 0.5)
    plane.SetNormal(0, 0, 1)
    cutter = vtk.vtkCutter()
    cutter.SetCutFunction(plane)
    cutter.SetInputConnection(reader.GetOutputPort())
    cutter.Update()
    return cutter


def render(cutter, png):
    polys = cutter.GetOutput()
    vs = polys.GetCellData().GetArray("vs")
    if vs is None:
        fail("the cut carries no vs")
    mapper = vtk.vtkPolyDataMapper()
    mapper.SetInputConnection(cutter.GetOutputPort())
    mapper.SetScalarModeToUseCellFieldData()
    mapper.SelectColorArray("vs")
    mapper.SetScalarRange(vs.GetRange())
    mapper.ScalarVisibilityOn()
    actor = vtk.vtkActor()
    actor.SetMapper(mapper)
    renderer = vtk.vtkRenderer()
    renderer.AddActor(actor)
    renderer.SetBackground(1, 1, 1)
    window = vtk.vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.AddRenderer(renderer)
    window.SetSize(640, 480)
    renderer.ResetCamera()
    window.Render()
    grab = vtk.vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.Update()
    writer = vtk.vtkPNGWriter()
    writer.SetFileName(png)
    writer.SetInputConnection(grab.GetOutputPort())
    writer.Write()
    image = grab.GetOutput()
    w, h, _ = image.GetDimensions()
    pixels = vtk_to_numpy(image.GetPointData().GetScalars()).reshape(h, w, -1)[:, :, :3]
    return pixels


for name, reader in (("vtu", vtk.vtkXMLUnstructuredGridReader()),
                     ("pvtu", vtk.vtkXMLPUnstructuredGridReader())):
    reader.SetFileName(vtu if name == "vtu" else pvtu)
    reader.Update()
    cutter = cut_of(reader)
    ids = cutter.GetOutput().GetCellData().GetArray("element_id")
    if ids is None:
        fail(f"{name}: the cut carries no element_id")
    got = set(int(i) for i in vtk_to_numpy(ids))
    if got != want:
        fail(f"{name}: the cut holds {len(got)} elements, weaver query range finds {len(want)} "
             f"({len(got - want)} only in the cut, {len(want - got)} only in the query)")
    png = os.path.join(work, f"cut-{name}.png")
    pixels = render(cutter, png)
    if not os.path.getsize(png):
        fail(f"{name}: no PNG written")
    drawn = (pixels != 255).any(axis=2).mean()
    colours = len(np.unique(pixels.reshape(-1, 3), axis=0))
    if drawn < 0.2 or colours < 8:
        fail(f"{name}: the picture is blank ({drawn:.0%} of pixels drawn, {colours} colours)")
    print(f"check_render: {name}: the plane z = {T}.5 ticks cuts {len(got)} elements "
          f"(levels {sorted(levels_cut)}), as the range query; {png}: {drawn:.0%} drawn, "
          f"{colours} colours")
