#!/usr/bin/python3
"""The hanging cloth of tests/scenes/shared/cloth.yaml, undamped, for LAMMPS
(issue 17, item 5; scripts/lammps_cloth.sh runs it beside pdyn).

  cloth.py data FRAME0.csv NX NY OUT.data   LAMMPS data file from pdyn's frame 0
  cloth.py compare PDYN.csv LAMMPS.dump NX  largest position and velocity
                                            differences at the last frame

The cloth is an NX x NY grid (particle (i, j) has id j NX + i, row NY - 1 on
top), structural springs (ks = 1000 N/m, rest 0.01 m) and shear springs
(ks = 500 N/m, rest 0.01 sqrt 2 m), no damping and no drag, gravity 9.81 m/s^2
along -z, the two top corners pinned, every other particle moving at
1 m/s along +y. LAMMPS's harmonic bond has E = K (r - r0)^2, so K = ks / 2;
since the factor is 2, -2 K (r - r0) / r rounds exactly as pdyn's
-ks (r - r0) / r. The positions and velocities come from pdyn's own frame 0
(17 significant digits), so both programs start from the same bits.
"""
import csv
import math
import sys

KS_STRUCTURAL, KS_SHEAR = 1000.0, 500.0
REST_STRUCTURAL = 0.01
REST_SHEAR = 0.01 * math.sqrt(2.0)  # the same double as the scene's --set value (repr)


def read_frames(path):
    """{t: {id: (x, y, z, vx, vy, vz)}} from a pdyn csv."""
    frames = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            frames.setdefault(float(row["t"]), {})[int(row["id"])] = tuple(
                float(row[k]) for k in ("x", "y", "z", "vx", "vy", "vz"))
    return frames


def bonds(nx, ny):
    """(type, a, b) with 1-based LAMMPS ids: 1 structural, 2 shear."""
    pid = lambda i, j: j * nx + i + 1
    out = []
    for j in range(ny):
        for i in range(nx):
            if i + 1 < nx:
                out.append((1, pid(i, j), pid(i + 1, j)))
            if j + 1 < ny:
                out.append((1, pid(i, j), pid(i, j + 1)))
            if i + 1 < nx and j + 1 < ny:
                out.append((2, pid(i, j), pid(i + 1, j + 1)))
                out.append((2, pid(i + 1, j), pid(i, j + 1)))
    return out


def write_data(frame0, nx, ny, out):
    frames = read_frames(frame0)
    state = frames[min(frames)]
    n = nx * ny
    assert len(state) == n, f"{frame0}: {len(state)} particles, expected {n}"
    b = bonds(nx, ny)
    lo = [min(s[k] for s in state.values()) - 0.01 for k in range(3)]
    hi = [max(s[k] for s in state.values()) + 0.01 for k in range(3)]
    with open(out, "w") as f:
        f.write(f"pdyn hanging cloth {nx} x {ny}, undamped (bench/lammps/cloth.py)\n\n")
        f.write(f"{n} atoms\n{len(b)} bonds\n1 atom types\n2 bond types\n\n")
        for k, axis in enumerate("xyz"):
            f.write(f"{lo[k]!r} {hi[k]!r} {axis}lo {axis}hi\n")
        f.write("\nMasses\n\n1 0.0001\n\nBond Coeffs # harmonic\n\n")
        f.write(f"1 {KS_STRUCTURAL / 2!r} {REST_STRUCTURAL!r}\n")
        f.write(f"2 {KS_SHEAR / 2!r} {REST_SHEAR!r}\n\nAtoms # bond\n\n")
        for i in range(n):
            x, y, z = state[i][:3]
            f.write(f"{i + 1} 1 1 {x!r} {y!r} {z!r}\n")
        f.write("\nVelocities\n\n")
        for i in range(n):
            vx, vy, vz = state[i][3:]
            f.write(f"{i + 1} {vx!r} {vy!r} {vz!r}\n")
        f.write("\nBonds\n\n")
        for k, (t, a, c) in enumerate(b):
            f.write(f"{k + 1} {t} {a} {c}\n")


def read_dump(path):
    """{id (0-based): (x, y, z, vx, vy, vz)} from a LAMMPS custom dump."""
    with open(path) as f:
        lines = f.read().splitlines()
    start = next(k for k, l in enumerate(lines) if l.startswith("ITEM: ATOMS"))
    cols = lines[start].split()[2:]
    out = {}
    for l in lines[start + 1:]:
        v = dict(zip(cols, l.split()))
        out[int(v["id"]) - 1] = tuple(float(v[k]) for k in ("x", "y", "z", "vx", "vy", "vz"))
    return out


def compare(pdyn_csv, dump, nx):
    frames = read_frames(pdyn_csv)
    mine = frames[max(frames)]
    theirs = read_dump(dump)
    assert mine.keys() == theirs.keys(), "different particle sets"
    dx = max(abs(mine[i][k] - theirs[i][k]) for i in mine for k in range(3))
    dv = max(abs(mine[i][k] - theirs[i][k]) for i in mine for k in range(3, 6))
    size = (nx - 1) * REST_STRUCTURAL
    print(f"agreement: max |x_pdyn - x_lammps| = {dx:.3g} m = {dx / size:.3g} of the cloth's "
          f"size, max |v_pdyn - v_lammps| = {dv:.3g} m/s")
    return dx / size


if __name__ == "__main__":
    if len(sys.argv) == 6 and sys.argv[1] == "data":
        write_data(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5])
    elif len(sys.argv) == 5 and sys.argv[1] == "compare":
        rel = compare(sys.argv[2], sys.argv[3], int(sys.argv[4]))
        # Rounding differences only: the sums run in another order (after 200
        # steps about 1e-15 of the size; scripts/lammps_cloth.sh).
        sys.exit(0 if rel <= 1e-12 else 1)
    else:
        sys.exit(__doc__)
