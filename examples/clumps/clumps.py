#!/usr/bin/env python3
"""The clump heap (in.clumps) beside its native twin (fix rigid/small), over seeds.

    python3 examples/clumps/clumps.py --lmp build/fix/lmp_fibre --workdir W [--seeds S ...]
        [--native-dt 0.001 --native-steps 40000] [--dt 0.025 --steps 1600] [--picture P.png]

Each seed runs native at its step and the fix at its own (both to the same simulated time);
prints per seed and as mean +- standard deviation the heap's height (the 99th percentile of
the spheres' tops), its spread (the standard deviation of x) and its angle of repose (a line
fitted to the surface, the highest top in cells of 1 x 4 diameters averaged across y, on both
flanks between 15% and 85% of the height), and the wall seconds.
"""

import argparse
import math
import os
import statistics
import subprocess
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def load(path):
    lines = open(path).read().splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith("ITEM: ATOMS")) + 1
    a = np.array([[float(v) for v in line.split()[2:6]] for line in lines[start:]])
    return a[:, 0], a[:, 1], a[:, 2] + a[:, 3]  # x, y, the sphere's top


def measure(path, ywidth):
    x, y, top = load(path)
    height = float(np.percentile(top, 99))
    xc = float(x.mean())
    d, h = [], []
    for lo in np.arange(0.0, 60.0, 1.0):
        tops = [top[(x >= lo) & (x < lo + 1) & (y >= ylo) & (y < ylo + 4)]
                for ylo in np.arange(0.0, ywidth, 4.0)]
        tops = [t.max() for t in tops if t.size]
        if tops:
            d.append(abs(lo + 0.5 - xc))
            h.append(sum(tops) / len(tops))
    d, h = np.array(d), np.array(h)
    flank = (h > 0.15 * height) & (h < 0.85 * height)
    slope = np.polyfit(d[flank], h[flank], 1)[0]
    return {"height": height, "spread": float(x.std()), "angle": math.degrees(math.atan(-slope))}


def run(args, mode, seed, dt, steps):
    cmd = [args.lmp, "-in", os.path.join(HERE, "in.clumps"), "-log", "log.%s.%d" % (mode, seed),
           "-var", "mode", mode, "-var", "seed", str(seed), "-var", "dt", str(dt), "-var",
           "steps", str(steps), "-var", "ywidth", str(args.ywidth)]
    t0 = time.time()
    subprocess.run(cmd, cwd=args.workdir, check=True, stdout=subprocess.DEVNULL)
    seconds = time.time() - t0
    out = measure(os.path.join(args.workdir, "dump.clumps.%s.%d" % (mode, seed)), args.ywidth)
    out["seconds"] = seconds
    return out


def picture(args, seed, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(2, 1, figsize=(8, 4.5), sharex=True)
    for ax, mode, title in zip(axes, ("native", "fibre"),
                               ("native: fix rigid/small, step 0.001",
                                "fix fibre_contact clumps molecule, step %g" % args.dt)):
        x, _, top = load(os.path.join(args.workdir, "dump.clumps.%s.%d" % (mode, seed)))
        ax.scatter(x, top - 0.5, s=2, c="k")
        ax.set_title(title, fontsize=9)
        ax.set_aspect("equal")
        ax.set_ylim(0, 12)
    axes[-1].set_xlabel("x (diameters)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--lmp", required=True)
    p.add_argument("--workdir", required=True)
    p.add_argument("--seeds", type=int, nargs="+",
                   default=[4767548, 1234567, 7654321, 2468024, 1357913])
    p.add_argument("--ywidth", type=int, default=24)
    p.add_argument("--native-dt", type=float, default=0.001)
    p.add_argument("--native-steps", type=int, default=40000)
    p.add_argument("--dt", type=float, default=0.025)
    p.add_argument("--steps", type=int, default=1600)
    p.add_argument("--picture")
    args = p.parse_args()
    args.lmp = os.path.abspath(args.lmp)
    os.makedirs(args.workdir, exist_ok=True)
    rows = {"native": [], "fibre": []}
    print("| seed | twin | height | spread | angle (deg) | wall s |\n|---|---|---|---|---|---|")
    for seed in args.seeds:
        for mode, dt, steps in (("native", args.native_dt, args.native_steps),
                                ("fibre", args.dt, args.steps)):
            r = run(args, mode, seed, dt, steps)
            rows[mode].append(r)
            print("| %d | %s | %.2f | %.2f | %.1f | %.1f |"
                  % (seed, mode, r["height"], r["spread"], r["angle"], r["seconds"]), flush=True)
    for mode, rs in rows.items():
        line = "| mean | %s |" % mode
        for key in ("height", "spread", "angle", "seconds"):
            v = [r[key] for r in rs]
            sd = statistics.stdev(v) if len(v) > 1 else 0.0
            line += " %.2f +- %.2f |" % (statistics.mean(v), sd)
        print(line)
    if args.picture:
        picture(args, args.seeds[0], args.picture)


if __name__ == "__main__":
    main()
