#!/usr/bin/env python3
"""Wall time of two commands, alternated: A B A B ..., the ratio A/B pair by pair.

    /usr/bin/python3 bench/pairs.py [-n PAIRS] 'COMMAND A' 'COMMAND B'

Prints each command's median wall time and the median, minimum and maximum
of the pairwise ratios. On a shared virtual machine a single run varies by
10-20% over seconds; alternating lets both commands meet the same slow and
fast spells, and the ratio of each pair cancels most of it. The commands
are split as a shell splits words (shlex) and run without a shell; their
output is discarded; a failing command stops the measurement.
"""

import argparse
import shlex
import statistics
import subprocess
import time


def wall(cmd):
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", type=int, default=5, help="pairs (default 5)")
    ap.add_argument("a")
    ap.add_argument("b")
    args = ap.parse_args()
    a, b = shlex.split(args.a), shlex.split(args.b)
    wall(a)  # warm-up: page cache, plugin libraries
    ta, tb = [], []
    for _ in range(args.n):
        ta.append(wall(a))
        tb.append(wall(b))
    ratios = [x / y for x, y in zip(ta, tb)]
    print(f"A {statistics.median(ta):.3f} s, B {statistics.median(tb):.3f} s (medians); "
          f"A/B {statistics.median(ratios):.3f} (min {min(ratios):.3f}, max {max(ratios):.3f}; "
          f"{args.n} pairs)")


if __name__ == "__main__":
    main()
