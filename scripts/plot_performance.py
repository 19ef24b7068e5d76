#!/usr/bin/env python3
"""Table and plot of the hanging-cloth benchmark (docs/performance.md).

    python3 scripts/plot_performance.py OUT_DIR PNG

OUT_DIR holds what scripts/bench.sh wrote: cloth.json (Google Benchmark
JSON), memory.jsonl and load.jsonl. Prints the Markdown table (median of
the repetitions, ns per particle-step, and each variant's ratio to the
hand-fused reference) and draws PNG with gnuplot (standard library only
here, so no matplotlib is needed).
"""
import json
import os
import subprocess
import sys
import tempfile

VARIANTS = [
    ("BM_fused", "fused reference", 1),
    ("BM_odeint", "Boost.Odeint rk4", 1),
    ("BM_pdyn_run", "pdyn run, 1 thread", 1),
    ("BM_pdyn_run", "pdyn run, 2 threads", 2),
    ("BM_pdyn_step", "pdyn solver step, 1 thread", 1),
    ("BM_pdyn_step", "pdyn solver step, 2 threads", 2),
]


def load(out_dir):
    with open(os.path.join(out_dir, "cloth.json")) as f:
        data = json.load(f)
    # name "BM_pdyn_run/316/2/min_time:1.000/real_time_median" -> (base, n, threads)
    table = {}
    for b in data["benchmarks"]:
        if b.get("aggregate_name", "median") != "median":
            continue
        parts = b["run_name"].split("/")
        base, n = parts[0], int(parts[1])
        threads = int(parts[2]) if len(parts) > 2 and parts[2].isdigit() else 1
        table[(base, n, threads)] = b["per_particle_step"] * 1e9  # s -> ns
    return table


def main():
    out_dir, png = sys.argv[1], sys.argv[2]
    table = load(out_dir)
    sizes = sorted({n for (_, n, _) in table})
    print("| variant | " + " | ".join(f"{n} x {n}" for n in sizes) + " |")
    print("|---|" + "---|" * len(sizes))
    for base, label, threads in VARIANTS:
        cells = []
        for n in sizes:
            v = table.get((base, n, threads))
            ref = table.get(("BM_fused", n, 1))
            cells.append("-" if v is None else f"{v:.1f} ns ({v / ref:.2f}x)")
        print(f"| {label} | " + " | ".join(cells) + " |")
    for n in sizes:
        one, two = table.get(("BM_pdyn_run", n, 1)), table.get(("BM_pdyn_run", n, 2))
        if one and two:
            print(f"\npdyn run speed-up, 2 threads over 1, {n} x {n}: {one / two:.2f}x", end="")
    print()

    with tempfile.TemporaryDirectory() as tmp:
        dat = os.path.join(tmp, "cloth.dat")
        with open(dat, "w") as f:
            for base, label, threads in VARIANTS:
                f.write(f'"{label}"\n')
                for n in sizes:
                    if (base, n, threads) in table:
                        f.write(f"{n * n} {table[(base, n, threads)]}\n")
                f.write("\n\n")
        script = f"""
set terminal pngcairo size 900,560 noenhanced font ",11"
set output "{png}"
set title "Hanging cloth, rk4: time per particle-step (lower is better; log scales)"
set logscale xy
set xlabel "particles"
set ylabel "ns per particle-step"

set key outside right
set grid
plot for [i=0:{len(VARIANTS) - 1}] "{dat}" index i using 1:2 with linespoints lw 2 title columnheader(1)
"""
        try:
            subprocess.run(["gnuplot"], input=script, text=True, check=True)
        except (OSError, subprocess.CalledProcessError):
            subprocess.run(["gnuplot"], input=script.replace("pngcairo", "png"), text=True,
                           check=True)
    print(f"plot written to {png}")


if __name__ == "__main__":
    main()
