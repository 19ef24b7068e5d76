#!/usr/bin/python3
"""Resume, interrupt and full-disk behaviour of every shipped writer.

    interrupt.py --pdyn PDYN --work DIR

One scene writes csv, energy, vtk and h5md at once (each on its own
schedule: every 7, 7, 5 and 10 steps), with a checkpoint every 20 steps:

 1. split: `--steps 100` (its end, step 100, is an extra frame for every
    writer but vtk's) then `--steps 200 --resume` equals one `--steps 200`
    run: csv, energy and .pvd byte for byte, the same set of .vtp files
    with the same bytes, and every HDF5 dataset and attribute equal;
 2. Ctrl-C: a run interrupted with SIGINT leaves files that VTK and h5py
    open (each .vtp, the .pvd's XML, the .h5), exits 130 with a checkpoint,
    and resumed to 200 steps equals the uninterrupted run;
 3. SIGKILL: a killed run leaves nothing under the final names of csv, pvd
    and h5 (only temporary files), and resumed from its last periodic
    checkpoint equals the uninterrupted run;
 4. full disk: with the file size limited (RLIMIT_FSIZE, so a write fails
    with EFBIG as on a full disk), the run stops with exit status 3 and a
    message naming the file, the checkpoint is written, no temporary file
    is left, and every output under its final name is complete up to its
    last whole frame; with the limit lifted the run resumes to the same
    files as an uninterrupted one.
"""
import argparse
import filecmp
import os
import resource
import shutil
import signal
import struct
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import h5py  # python3-h5py: a missing module fails the test
import numpy as np
import vtk   # python3-vtk9

FAILURES = []


def check(ok, what):
    if not ok:
        FAILURES.append(what)
        print("FAIL:", what, flush=True)


SCENE = """\
simulation: { dt: 0.005, steps: 200, solver: { type: rk4 } }
particles:
  - grid: { origin: [0, 0, 1], u: [0.1, 0, 0], v: [0, 0.1, 0], nx: 8, ny: 6, mass: 0.1,
            pin: [[0, 0], [-1, 0]], springs: { structural: { ks: 300, kd: 0.2 }, shear: { ks: 100 } } }
forces:
  - { type: gravity }
  - { type: drag, k: 0.01 }
colliders:
  - { type: sphere, center: [0.35, 0.25, 0.6], radius: 0.2 }
output:
  - { type: csv, path: out/run.csv, every: 7 }
  - { type: energy, path: out/energy.csv, every: 7 }
  - { type: vtk, path: out/run.pvd, every: 5, fields: [velocity, mass, fixed, force] }
  - { type: h5md, path: out/run.h5, every: 10, fields: [velocity, force], compression: 1 }
checkpoint: { path: out/run.ckpt, every: 20 }
"""


def pdyn(exe, cwd, *args, preexec=None):
    return subprocess.run([exe, *args], cwd=cwd, capture_output=True, text=True,
                          preexec_fn=preexec)


H5MD_LINE = "  - { type: h5md, path: out/run.h5, every: 10, fields: [velocity, force], compression: 1 }\n"


def fresh(work, name, text=SCENE):
    d = os.path.join(work, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    with open(os.path.join(d, "scene.yaml"), "w") as f:
        f.write(text)
    return d


def h5_tree(path):
    """{name: (attrs, data)} of every group and dataset."""
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            attrs = {k: (v.tobytes() if isinstance(v, np.ndarray) else v)
                     for k, v in obj.attrs.items() if k != "particles_group"}
            data = obj[()].tobytes() if isinstance(obj, h5py.Dataset) else None
            out[name] = (attrs, data)
        f.visititems(visit)
    return out


def same_outputs(a, b, what, h5=True):
    for f in ("run.csv", "energy.csv", "run.pvd"):
        check(filecmp.cmp(os.path.join(a, f), os.path.join(b, f), shallow=False),
              f"{what}: out/{f} differs from the uninterrupted run's")
    va = sorted(os.listdir(os.path.join(a, "run")))
    vb = sorted(os.listdir(os.path.join(b, "run")))
    check(va == vb, f"{what}: the .vtp files differ: {len(va)} vs {len(vb)}")
    differ = [f for f in va if f in vb and not filecmp.cmp(
        os.path.join(a, "run", f), os.path.join(b, "run", f), shallow=False)]
    check(not differ, f"{what}: {len(differ)} .vtp files differ, e.g. {differ[:3]}")
    if h5:
        ta, tb = h5_tree(os.path.join(a, "run.h5")), h5_tree(os.path.join(b, "run.h5"))
        check(ta.keys() == tb.keys(), f"{what}: run.h5 has other objects")
        differ = [k for k in ta if k in tb and ta[k] != tb[k]]
        check(not differ, f"{what}: run.h5 objects differ: {differ}")
    return len(va)


def opens(out, what, h5=True):
    """Every output under its final name opens with its format's reader."""
    root = ET.parse(os.path.join(out, "run.pvd")).getroot()
    files = [d.get("file") for d in root.iter("DataSet")]
    bad = 0
    for f in set(files):
        r = vtk.vtkXMLPolyDataReader()
        r.SetFileName(os.path.join(out, f))
        r.Update()
        bad += r.GetErrorCode() != 0 or r.GetOutput().GetNumberOfPoints() == 0
    check(bad == 0, f"{what}: {bad} of {len(set(files))} .vtp files do not open")
    if h5:
        with h5py.File(os.path.join(out, "run.h5"), "r") as f:
            n = f["particles/all/position/value"].shape[0]
            check(f["particles/all/position/time"].shape[0] == n, f"{what}: run.h5 time/value differ")
    return len(files)


def checkpoint_step(path):
    """The step of a checkpoint (host/src/checkpoint.cpp: magic, u32 version,
    u64 length, then string scene_file, string scene_text, i64 step)."""
    with open(path, "rb") as f:
        data = f.read()
    at = 20
    for _ in range(2):
        at += 8 + struct.unpack_from("<Q", data, at)[0]
    return struct.unpack_from("<q", data, at)[0]


def temporaries(out):
    found = []
    for root, _, files in os.walk(out):
        found += [f for f in files if ".tmp-" in f]
    return found


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pdyn", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    exe = os.path.abspath(a.pdyn)
    os.makedirs(a.work, exist_ok=True)

    ref = fresh(a.work, "whole")
    r = pdyn(exe, ref, "run", "scene.yaml", "-q")
    check(r.returncode == 0, f"whole run: exit {r.returncode}: {r.stderr}")
    frames = opens(os.path.join(ref, "out"), "whole run")
    refout = os.path.join(ref, "out")

    # 1. split at step 100
    d = fresh(a.work, "split")
    r = pdyn(exe, d, "run", "scene.yaml", "--steps", "100", "-q")
    check(r.returncode == 0, f"split: first half exit {r.returncode}: {r.stderr}")
    r = pdyn(exe, d, "run", "scene.yaml", "-q", "--resume", "out/run.ckpt")
    check(r.returncode == 0, f"split: resumed exit {r.returncode}: {r.stderr}")
    same_outputs(refout, os.path.join(d, "out"), "split at step 100")
    check(not temporaries(os.path.join(d, "out")), "split: temporary files left")

    # 2. Ctrl-C once the first periodic checkpoint exists
    d = fresh(a.work, "sigint")
    long_run = [exe, "run", "scene.yaml", "--steps", "100000000", "-q"]
    child = subprocess.Popen(long_run, cwd=d, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    ckpt = os.path.join(d, "out/run.ckpt")
    t0 = time.time()
    while not os.path.exists(ckpt) and child.poll() is None and time.time() - t0 < 60:
        time.sleep(0.005)
    child.send_signal(signal.SIGINT)
    _, err = child.communicate(timeout=60)
    check(child.returncode == 130, f"sigint: exit {child.returncode}: {err.decode()}")
    opens(os.path.join(d, "out"), "after Ctrl-C")
    check(not temporaries(os.path.join(d, "out")), "sigint: temporary files left")
    with open(os.path.join(d, "out/run.csv")) as f:
        rows = sum(1 for _ in f) - 1
    steps = 0
    with open(os.path.join(d, "out/energy.csv")) as f:
        last = f.readlines()[-1]
        steps = round(float(last.split(",")[0]) / 0.005)
    check(rows % 48 == 0 and steps > 0, f"sigint: {rows} csv rows, stopped at step {steps}")
    # Resumed to at least twice its length, against a whole run as long.
    n = str(max(200, 2 * steps))
    whole = fresh(a.work, "sigint-whole")
    r = pdyn(exe, whole, "run", "scene.yaml", "--steps", n, "-q")
    check(r.returncode == 0, f"sigint reference: exit {r.returncode}: {r.stderr}")
    r = pdyn(exe, d, "run", "scene.yaml", "--steps", n, "-q", "--resume", "out/run.ckpt")
    check(r.returncode == 0, f"sigint: resumed exit {r.returncode}: {r.stderr}")
    same_outputs(os.path.join(whole, "out"), os.path.join(d, "out"), f"Ctrl-C at step {steps}")

    # 3. SIGKILL after the first periodic checkpoint
    d = fresh(a.work, "sigkill")
    child = subprocess.Popen(long_run, cwd=d, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    t0 = time.time()
    while not os.path.exists(ckpt.replace("sigint", "sigkill")) and child.poll() is None \
            and time.time() - t0 < 60:
        time.sleep(0.005)
    time.sleep(0.05)
    child.kill()
    child.communicate(timeout=60)
    out = os.path.join(d, "out")
    for f in ("run.csv", "energy.csv", "run.pvd", "run.h5"):
        check(not os.path.exists(os.path.join(out, f)), f"sigkill: out/{f} exists after a kill")
    check(len(temporaries(out)) >= 4, f"sigkill: temporaries {temporaries(out)}")
    n = str(max(200, 2 * checkpoint_step(os.path.join(out, "run.ckpt"))))
    whole = fresh(a.work, "sigkill-whole")
    r = pdyn(exe, whole, "run", "scene.yaml", "--steps", n, "-q")
    check(r.returncode == 0, f"sigkill reference: exit {r.returncode}: {r.stderr}")
    r = pdyn(exe, d, "run", "scene.yaml", "--steps", n, "-q", "--resume", "out/run.ckpt")
    check(r.returncode == 0, f"sigkill: resumed exit {r.returncode}: {r.stderr}")
    if r.returncode == 0:
        same_outputs(os.path.join(whole, "out"), out, "after SIGKILL")
        # (A checkpoint being written when the kill came may stay as
        # run.ckpt.tmp-PID: the host's, not a writer's.)
        left = [t for t in temporaries(out) if not t.startswith("run.ckpt.tmp-")]
        check(not left, f"sigkill: temporaries left after resuming: {left}")

    # 4. a full disk (files limited to 60 kB: the csv fails first), without
    # the h5md writer, whose file HDF5 cannot complete after a failed write
    # (case 5)
    text = SCENE.replace(H5MD_LINE, "")
    check(text != SCENE, "the h5md line was not found in the scene")
    ref = fresh(a.work, "full-whole", text)
    r = pdyn(exe, ref, "run", "scene.yaml", "-q")
    check(r.returncode == 0, f"full disk reference: exit {r.returncode}: {r.stderr}")
    refout = os.path.join(ref, "out")
    d = fresh(a.work, "full", text)

    def limited(size):
        def pre():
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
            resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
        return pre

    r = pdyn(exe, d, "run", "scene.yaml", "-q", preexec=limited(60000))
    check(r.returncode == 3, f"full disk: exit {r.returncode} (expected 3): {r.stderr}")
    check("out/run.csv: cannot write output file (File too large)" in r.stderr,
          f"full disk: the message does not name the file: {r.stderr}")
    check("checkpoint (out/run.ckpt)" in r.stderr, f"full disk: no checkpoint named: {r.stderr}")
    out = os.path.join(d, "out")
    check(not temporaries(out), f"full disk: temporaries left: {temporaries(out)}")
    with open(os.path.join(out, "run.csv"), "rb") as f:
        data = f.read()
    rows = data.count(b"\n") - 1
    check(data.endswith(b"\n") and rows % 48 == 0 and 0 < len(data) <= 60000,
          f"full disk: run.csv is not whole frames ({rows} rows, {len(data)} bytes)")
    check(data == open(os.path.join(refout, "run.csv"), "rb").read()[:len(data)],
          "full disk: run.csv is not a prefix of the uninterrupted run's")
    opens(out, "after a full disk", h5=False)
    r = pdyn(exe, d, "run", "scene.yaml", "-q", "--resume", "out/run.ckpt")
    check(r.returncode == 0, f"full disk: resumed exit {r.returncode}: {r.stderr}")
    same_outputs(refout, out, "after a full disk, resumed", h5=False)

    # 5. h5md on a full disk: the run stops naming the file, and nothing is
    # left under its final name or a temporary one.
    d = fresh(a.work, "full-h5", SCENE.replace("every: 7 }", "every: 700 }"))
    r = pdyn(exe, d, "run", "scene.yaml", "-q", preexec=limited(60000))
    out = os.path.join(d, "out")
    check(r.returncode in (1, 3) and "out/run.h5: cannot write output file" in r.stderr,
          f"h5md on a full disk: exit {r.returncode}: {r.stderr}")
    check(not os.path.exists(os.path.join(out, "run.h5")) and not temporaries(out),
          f"h5md on a full disk: left {os.listdir(out)}")

    if FAILURES:
        print(f"writers.interrupt: {len(FAILURES)} failures")
        return 1
    print(f"writers.interrupt: split, Ctrl-C at step {steps}, SIGKILL and a full disk all "
          f"resume to the uninterrupted run's files ({frames} vtk frames, csv, energy, h5md)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
