#!/usr/bin/python3
"""Read-back tests of the vtk and h5md writers with the formats' own readers.

    readback.py vtk|h5md --pdyn PDYN --work DIR

Runs small scenes with pdyn, writing each frame through the writer under
test and through the csv writer (17 significant digits: every double reads
back exactly), then reads the writer's files with VTK's own XML reader
(python3-vtk9) or with h5py (python3-h5py) and compares every value bit for
bit: times, positions, velocities against the csv rows; ids, masses, fixed
flags, radii and types against the scene; forces against m g (a scene whose
only force is gravity, so f = m g is one rounding, the same in Python); the
springs (lines) against the grid's structural pairs; the obstacles against
the colliders. The modules are imported unconditionally: a machine without
them fails the test rather than skipping it. Exit status 0 when every
comparison holds, 1 with one line per failure otherwise.
"""
import argparse
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET

FAILURES = []


def check(ok, what):
    if not ok:
        FAILURES.append(what)
        print("FAIL:", what, flush=True)


def bits(x):
    return struct.pack("<d", float(x))


def same(a, b):
    """Bit-identical doubles (0.0 and -0.0 differ, as they do in memory)."""
    return bits(a) == bits(b)


NX, NY = 6, 5
CLOTH = """\
simulation: {{ dt: 0.01, steps: 40, solver: {{ type: rk4 }} }}
particles:
  - grid: {{ origin: [0, 0, 1], u: [0.1, 0, 0], v: [0, 0.1, 0], nx: {nx}, ny: {ny}, mass: 0.25,
            pin: [[0, 0], [-1, 0]], particle_radius: 0.02, particle_type: 3,
            springs: {{ structural: {{ ks: 200, kd: 0.5 }} }} }}
forces:
  - {{ type: gravity }}
colliders:
  - {{ type: plane, point: [0, 0, 0.2] }}
  - {{ type: sphere, center: [0.25, 0.2, 0.6], radius: 0.15 }}
output:
{writer}
  - {{ type: csv, path: out/cloth.csv, every: 5 }}
"""
FALLING = """\
simulation: {{ dt: 0.01, steps: 12 }}
particles:
  - {{ position: [0, 0, 10], mass: 0.3 }}
  - {{ position: [1, 0, 10], mass: 1.7, velocity: [0.5, 0, 2] }}
  - {{ position: [2, 0, 10], mass: 0.1, fixed: true }}
forces:
  - {{ type: gravity, g: [0.1, -0.2, -9.81] }}
output:
{writer}
  - {{ type: csv, path: out/fall.csv, every: 4 }}
"""
G = (0.1, -0.2, -9.81)


def run(pdyn, work, name, text):
    scene = os.path.join(work, name + ".yaml")
    with open(scene, "w") as f:
        f.write(text)
    r = subprocess.run([pdyn, "run", scene, "-q"], cwd=work, capture_output=True, text=True)
    check(r.returncode == 0, f"{name}: pdyn run exited {r.returncode}: {r.stderr.strip()}")


def csv_frames(path):
    """[(t, [(x, y, z)], [(vx, vy, vz)])] from a csv writer's file."""
    frames = {}
    order = []
    with open(path) as f:
        next(f)
        for line in f:
            c = line.strip().split(",")
            t = float(c[0])
            if t not in frames:
                frames[t] = ([], [])
                order.append(t)
            frames[t][0].append(tuple(float(v) for v in c[2:5]))
            frames[t][1].append(tuple(float(v) for v in c[5:8]))
    return [(t, frames[t][0], frames[t][1]) for t in order]


def structural_pairs():
    pairs = set()
    for j in range(NY):
        for i in range(NX):
            k = j * NX + i
            if i + 1 < NX:
                pairs.add((k, k + 1))
            if j + 1 < NY:
                pairs.add((k, k + NX))
    return pairs


def compare_frames(name, got, want, values_per_frame):
    """got/want: [(t, x, v)]; every double bit for bit."""
    check(len(got) == len(want), f"{name}: {len(got)} frames read back, {len(want)} written")
    mismatches = 0
    for (tg, xg, vg), (tw, xw, vw) in zip(got, want):
        mismatches += not same(tg, tw)
        check(len(xg) == len(xw), f"{name}: t = {tw}: {len(xg)} particles, expected {len(xw)}")
        for a, b in zip(xg, xw):
            mismatches += sum(not same(p, q) for p, q in zip(a, b))
        for a, b in zip(vg, vw):
            mismatches += sum(not same(p, q) for p, q in zip(a, b))
    check(mismatches == 0, f"{name}: {mismatches} values differ from the csv rows")
    return sum(values_per_frame(f) for f in want)


# ---------------------------------------------------------------------------
# vtk

def vtk_test(pdyn, work):
    import vtk  # noqa: F401  (python3-vtk9: VTK's own reader)
    from vtkmodules.util.numpy_support import vtk_to_numpy

    def read(path):
        r = vtk.vtkXMLPolyDataReader()
        r.SetFileName(path)
        r.Update()
        check(r.GetErrorCode() == 0, f"{path}: VTK reader error {r.GetErrorCode()}")
        return r.GetOutput()

    def array(poly, name):
        a = poly.GetPointData().GetArray(name)
        check(a is not None, f"no point data '{name}'")
        return vtk_to_numpy(a) if a is not None else None

    def collection(pvd):
        root = ET.parse(pvd).getroot()
        check(root.get("type") == "Collection", f"{pvd}: not a VTK collection")
        return [(float(d.get("timestep")), d.get("part"), d.get("file"))
                for d in root.iter("DataSet")]

    # The cloth: positions, velocities, ids, masses, fixed, radii, types, springs, obstacles.
    run(pdyn, work, "cloth", CLOTH.format(
        nx=NX, ny=NY,
        writer="  - { type: vtk, path: out/cloth.pvd, every: 5, "
               "fields: [id, velocity, mass, fixed, radius, type, image] }"))
    pvd = os.path.join(work, "out/cloth.pvd")
    entries = collection(pvd)
    frames = [e for e in entries if e[1] == "0"]
    obstacles = [e for e in entries if e[1] == "1"]
    check(len(obstacles) == len(frames), f"{len(obstacles)} obstacle entries for {len(frames)} frames")
    n = NX * NY
    got = []
    pinned = {0, NX - 1}
    value_count = 0
    for t, _, file in frames:
        poly = read(os.path.join(work, "out", file))
        x = vtk_to_numpy(poly.GetPoints().GetData())
        check(poly.GetPoints().GetData().GetDataType() == vtk.VTK_DOUBLE, f"{file}: points not Float64")
        v = array(poly, "velocity")
        got.append((t, [tuple(p) for p in x], [tuple(p) for p in v]))
        check(list(array(poly, "id")) == list(range(n)), f"{file}: ids are not 0..{n - 1}")
        check(all(same(m, 0.25) for m in array(poly, "mass")), f"{file}: masses are not 0.25")
        check([int(f) for f in array(poly, "fixed")] == [int(i in pinned) for i in range(n)],
              f"{file}: fixed flags differ from the pins")
        check(all(same(r, 0.02) for r in array(poly, "radius")), f"{file}: radii are not 0.02")
        check(all(int(k) == 3 for k in array(poly, "type")), f"{file}: types are not 3")
        check(all(int(k) == 0 for k in array(poly, "image").ravel()), f"{file}: image counts not 0")
        value_count += 5 * n
        check(poly.GetNumberOfVerts() == n, f"{file}: {poly.GetNumberOfVerts()} vertices, expected {n}")
        lines = poly.GetLines()
        ids = vtk_to_numpy(lines.GetConnectivityArray())
        offsets = vtk_to_numpy(lines.GetOffsetsArray())
        pairs = {tuple(sorted(ids[offsets[k]:offsets[k + 1]])) for k in range(len(offsets) - 1)}
        check(len(offsets) - 1 == len(structural_pairs()) and pairs == structural_pairs(),
              f"{file}: lines are not the {len(structural_pairs())} structural springs")
    value_count += compare_frames("vtk cloth", got, csv_frames(os.path.join(work, "out/cloth.csv")),
                                  lambda f: 6 * len(f[1]) + 1)
    # Obstacles: the plane z = 0.2 as a square, the sphere's vertices at its radius.
    poly = read(os.path.join(work, "out", obstacles[0][2]))
    which = vtk_to_numpy(poly.GetCellData().GetArray("obstacle"))
    pts = vtk_to_numpy(poly.GetPoints().GetData())
    check(sorted(set(int(w) for w in which)) == [0, 1], "obstacles: not two shapes (plane, sphere)")
    plane_cells = [k for k in range(poly.GetNumberOfCells()) if which[k] == 0]
    check(len(plane_cells) == 1, f"obstacles: the plane is {len(plane_cells)} cells, expected 1")
    cell = poly.GetCell(plane_cells[0])
    zs = [pts[cell.GetPointId(k)][2] for k in range(cell.GetNumberOfPoints())]
    check(cell.GetNumberOfPoints() == 4 and all(abs(z - 0.2) < 1e-15 for z in zs),
          f"obstacles: the plane's corners are not at z = 0.2: {zs}")
    worst = 0.0
    for k in range(poly.GetNumberOfCells()):
        if which[k] != 1:
            continue
        c = poly.GetCell(k)
        for j in range(c.GetNumberOfPoints()):
            p = pts[c.GetPointId(j)]
            r = math.dist(p, (0.25, 0.2, 0.6))
            worst = max(worst, abs(r - 0.15))
    check(worst < 1e-12, f"obstacles: sphere vertices off its surface by {worst}")

    # Forces: gravity alone, f = m g bit for bit.
    run(pdyn, work, "fall", FALLING.format(
        writer="  - { type: vtk, path: out/fall.pvd, every: 4, fields: [force, mass] }"))
    masses = (0.3, 1.7, 0.1)
    bad = 0
    fall = [e for e in collection(os.path.join(work, "out/fall.pvd")) if e[1] == "0"]
    for t, _, file in fall:
        poly = read(os.path.join(work, "out", file))
        f = array(poly, "force")
        for i, m in enumerate(masses):
            bad += sum(not same(f[i][k], m * G[k]) for k in range(3))
    check(bad == 0, f"vtk fall: {bad} force components differ from m g")
    want = csv_frames(os.path.join(work, "out/fall.csv"))
    check([e[0] for e in fall] == [w[0] for w in want], "vtk fall: frame times differ from the csv")
    value_count += 3 * len(masses) * len(fall)
    return value_count, len(frames) + len(fall)


# ---------------------------------------------------------------------------
# h5md

def h5md_test(pdyn, work):
    import h5py  # python3-h5py
    import numpy as np

    run(pdyn, work, "cloth", CLOTH.format(
        nx=NX, ny=NY,
        writer="  - { type: h5md, path: out/cloth.h5, every: 5, "
               "fields: [id, velocity, mass, fixed, radius, type, image], compression: 4 }"))
    n = NX * NY
    value_count = 0
    with h5py.File(os.path.join(work, "out/cloth.h5"), "r") as f:
        # H5MD 1.1, section "H5MD metadata": version [1, 1], author name, creator name and version.
        h5md = f["h5md"]
        check(list(h5md.attrs["version"]) == [1, 1], f"h5md version {list(h5md.attrs['version'])}")
        check("name" in h5md["author"].attrs, "h5md/author has no name")
        check(h5md["creator"].attrs["name"] in (b"pdyn", "pdyn"), "h5md/creator name is not pdyn")
        check("version" in h5md["creator"].attrs, "h5md/creator has no version")
        group = f["particles/all"]
        box = group["box"]
        check(int(box.attrs["dimension"]) == 3, "box dimension is not 3")
        check([b.decode() if isinstance(b, bytes) else b for b in box.attrs["boundary"]]
              == ["none"] * 3, f"box boundary {list(box.attrs['boundary'])}")
        pos = group["position"]
        steps, times, x = pos["step"][()], pos["time"][()], pos["value"][()]
        check(pos["value"].chunks is not None, "position/value is not chunked")
        check(pos["value"].compression == "gzip", "position/value is not gzip-compressed")
        check(x.shape[1:] == (n, 3), f"position/value shape {x.shape}")
        v = group["velocity/value"][()]
        want = csv_frames(os.path.join(work, "out/cloth.csv"))
        got = [(times[k], [tuple(p) for p in x[k]], [tuple(p) for p in v[k]])
               for k in range(len(times))]
        value_count += compare_frames("h5md cloth", got, want, lambda fr: 6 * len(fr[1]) + 1)
        cloth_frames = len(want)
        check(list(steps) == [5 * k for k in range(len(want))], f"position/step {list(steps)}")
        check(all(same(m, 0.25) for m in group["mass"][()].ravel()), "mass is not 0.25")
        check(list(group["id"][()].ravel()) == list(range(n)), "id is not 0..N-1")
        pinned = {0, NX - 1}
        check([int(b) for b in group["fixed"][()].ravel()] == [int(i in pinned) for i in range(n)],
              "fixed differs from the pins")
        check(all(same(r, 0.02) for r in group["radius"][()].ravel()), "radius is not 0.02")
        check(all(int(k) == 3 for k in group["species"][()].ravel()), "species (type) is not 3")
        img = group["image/value"][()]
        check(img.shape == (len(want), n, 3) and not img.any(), "image is not all 0")
        # Connectivity (H5MD "connectivity" module): the structural springs.
        bonds = f["connectivity/all/springs"][()] if "connectivity/all/springs" in f else None
        check(bonds is not None, "no connectivity/all/springs dataset")
        if bonds is not None:
            got_pairs = {tuple(sorted(int(i) for i in b)) for b in bonds}
            check(got_pairs == structural_pairs() and len(bonds) == len(structural_pairs()),
                  "connectivity/all/springs are not the structural springs")
        value_count += 4 * n

    run(pdyn, work, "fall", FALLING.format(
        writer="  - { type: h5md, path: out/fall.h5, every: 4, fields: [force, velocity] }"))
    masses = (0.3, 1.7, 0.1)
    with h5py.File(os.path.join(work, "out/fall.h5"), "r") as f:
        force = f["particles/all/force/value"][()]
        bad = sum(not same(force[k][i][c], masses[i] * G[c])
                  for k in range(force.shape[0]) for i in range(3) for c in range(3))
        check(bad == 0, f"h5md fall: {bad} force components differ from m g")
        want = csv_frames(os.path.join(work, "out/fall.csv"))
        t = f["particles/all/position/time"][()]
        check([float(a) for a in t] == [w[0] for w in want], "h5md fall: times differ from the csv")
        value_count += force.size
    return value_count, cloth_frames + len(want)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("writer", choices=["vtk", "h5md"])
    ap.add_argument("--pdyn", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    a.pdyn = os.path.abspath(a.pdyn)
    shutil.rmtree(a.work, ignore_errors=True)
    os.makedirs(a.work)
    values, frames = (vtk_test if a.writer == "vtk" else h5md_test)(a.pdyn, a.work)
    if FAILURES:
        print(f"{a.writer} read-back: {len(FAILURES)} failures")
        return 1
    print(f"{a.writer} read-back: {values} values in {frames} frames identical bit for bit")
    return 0


if __name__ == "__main__":
    sys.exit(main())
