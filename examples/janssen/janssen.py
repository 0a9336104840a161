#!/usr/bin/env python3
"""Janssen test: side-wall pressure with depth in a tall bin, fix fibre_contact against its
native twin (in.janssen, in.janssen.native: one pair_coeff line, the same spheres).

  janssen.py run    --workdir DIR [--seeds 4767 1031 2203] [--lmp L] [--native N] [--var K V]
  janssen.py report --workdir DIR [--seeds ...]

`run` runs both twins per seed in DIR/<method>_<seed>; `report` reads the settled pack's 10
snapshots, bins the side walls' normal forces by height (bins of 1, the largest diameter)
into a pressure p(z) = sum F / (4 W dz). It reports the deep pressure, the mean of p over
2 <= z <= h - 8 (h: the free surface, the mean height of the top 2% of the spheres; a bin
there is more than 1.5 Janssen lengths deep), the fit of Janssen's law
p(z) = p_sat (1 - exp(-(h - z) / lambda)) over 2 <= z <= h - 1 with lambda <= 20, and the
floor's share of the weight (the apparent mass).
"""

import argparse
import os
import shutil
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


def frames(path):
    """The frames of a LAMMPS text dump: (step, column names, array) each."""
    out = []
    with open(path) as f:
        lines = f.read().split("\n")
    i = 0
    while i < len(lines):
        if lines[i].startswith("ITEM: TIMESTEP"):
            step, n = int(lines[i + 1]), int(lines[i + 3])
            cols = lines[i + 8].split()[2:]
            rows = [list(map(float, line.split())) for line in lines[i + 9:i + 9 + n]]
            out.append((step, cols, np.array(rows).reshape(n, len(cols))))
            i += 9 + n
        else:
            i += 1
    return out


def log_value(path, key):
    """A number printed as `key value` on the deck's 'janssen:' line."""
    with open(path) as f:
        for line in f:
            if line.startswith("janssen:"):
                words = line.split()
                return float(words[words.index(key) + 1])
    raise RuntimeError("%s: no 'janssen:' line" % path)


def side_forces(run_dir, method):
    """Per snapshot: the side walls' normal forces with their heights, the floor's load and
    the weight of the pack."""
    atoms = frames(os.path.join(run_dir, "janssen.%s.atoms" % method))
    walls = frames(os.path.join(run_dir, "janssen.%s.walls" % method))
    log = os.path.join(run_dir, "log." + method)
    dt, width = log_value(log, "dt"), log_value(log, "W")
    by_step = {step: data for step, _, data in walls}
    out = []
    for step, cols, a in atoms:
        z_of = dict(zip(a[:, cols.index("id")].astype(int), a[:, cols.index("z")]))
        r = a[:, cols.index("radius")]
        weight = 9.81 * np.sum(4.0 / 3.0 * np.pi * r ** 3)  # density 1
        w = by_step[step]
        if method == "fibre":  # local rows: atom, wall (1, 2: sides; 3: floor), impulse
            side = w[(w[:, 1] == 1) | (w[:, 1] == 2)]
            heights = np.array([z_of[int(i)] for i in side[:, 0]])
            forces = side[:, 2] / dt
            floor = np.sum(w[w[:, 1] == 3][:, 2]) / dt
        else:  # per atom: id z fx (x walls) fy (y walls) fz (floor)
            heights = w[:, 1]
            forces = np.abs(w[:, 2]) + np.abs(w[:, 3])
            floor = np.sum(w[:, 4])
        z = np.sort(a[:, cols.index("z")])
        top = float(np.mean(z[-max(1, len(z) // 50):]))
        out.append((heights, forces, floor, weight, width, top))
    return out


def profile(snapshots, dz=1.0):
    """Bin centres and the mean side-wall pressure in each bin over the snapshots."""
    top = max(s[5] for s in snapshots) + 1.0
    edges = np.arange(0.0, top + dz, dz)
    p = np.zeros(len(edges) - 1)
    for heights, forces, _, _, width, _ in snapshots:
        sums, _ = np.histogram(heights, bins=edges, weights=forces)
        p += sums / (4.0 * width * dz)
    return 0.5 * (edges[1:] + edges[:-1]), p / len(snapshots)


def fit_janssen(z, p, top):
    """Least squares p_sat (1 - exp(-(h - z) / lambda)) over 2 <= z <= h - 1: (p_sat, lambda,
    h, rms misfit / p_sat)."""
    best = None
    for h in np.arange(top - 4.0, top + 0.51, 0.1):
        keep = (z >= 2.0) & (z <= h - 1.0)
        for lam in np.arange(0.5, 20.0, 0.05):
            shape = 1.0 - np.exp(-(h - z[keep]) / lam)
            psat = np.dot(shape, p[keep]) / np.dot(shape, shape)
            res = np.sqrt(np.mean((psat * shape - p[keep]) ** 2))
            if best is None or res < best[3]:
                best = (psat, lam, h, res)
    return best[0], best[1], best[2], best[3] / best[0]


def measure(run_dir, method):
    snaps = side_forces(run_dir, method)
    z, p = profile(snaps)
    top = float(np.mean([s[5] for s in snaps]))
    psat, lam, h, misfit = fit_janssen(z, p, top)
    floor_share = float(np.mean([s[2] / s[3] for s in snaps]))
    deep = (z >= 2.0) & (z <= top - 8.0)
    return {"deep": float(np.mean(p[deep])), "p_sat": psat, "lambda": lam, "surface": top,
            "misfit": misfit, "floor_share": floor_share, "z": z, "p": p}


def run(args):
    for seed in args.seeds:
        for method, exe, deck in (("fibre", args.lmp, "in.janssen"),
                                  ("native", args.native, "in.janssen.native")):
            if args.only and method != args.only:
                continue
            work = os.path.join(args.workdir, "%s_%s" % (method, seed))
            os.makedirs(work, exist_ok=True)
            for f in ("scene.janssen", "run.janssen", deck):
                shutil.copy(os.path.join(HERE, f), work)
            cmd = [exe, "-in", deck, "-var", "seed", str(seed), "-log", "log." + method,
                   "-screen", "none"]
            for k, v in args.var:
                cmd += ["-var", k, v]
            print(" ".join(cmd), "  (in %s)" % work, flush=True)
            subprocess.run(cmd, cwd=work, check=True)


def report(args):
    rows = {}
    for method in ("fibre", "native"):
        rows[method] = [measure(os.path.join(args.workdir, "%s_%s" % (method, s)), method)
                        for s in args.seeds]
    print("| twin | deep pressure (Pa) | fitted p_sat | lambda | surface | floor / weight |")
    print("|---|---|---|---|---|---|")
    for method, ms in rows.items():
        def stat(key, fmt):
            v = np.array([m[key] for m in ms])
            return (fmt % v.mean()) + (" (" + ", ".join(fmt % x for x in v) + ")" if len(v) > 1
                                       else "")
        print("| %s | %s | %s | %s | %s | %s |" % (
            method, stat("deep", "%.2f"), stat("p_sat", "%.2f"), stat("lambda", "%.2f"),
            stat("surface", "%.1f"), stat("floor_share", "%.3f")))
    for key in ("deep", "p_sat", "floor_share"):
        f = np.mean([m[key] for m in rows["fibre"]])
        n = np.mean([m[key] for m in rows["native"]])
        print("%s fibre / native: %.3f" % (key, f / n))
    print("pressure profile (seed %s), z: fibre / native" % args.seeds[0])
    f, n = rows["fibre"][0], rows["native"][0]
    for k in range(0, min(len(f["z"]), len(n["z"])), 2):
        print("  %5.1f  %7.2f  %7.2f" % (f["z"][k], f["p"][k], n["p"][k]))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("command", choices=("run", "report"))
    ap.add_argument("--workdir", required=True)
    ap.add_argument("--seeds", nargs="+", default=["4767", "1031", "2203"])
    ap.add_argument("--lmp", default=os.path.join(ROOT, "build", "fix", "lmp_fibre"))
    ap.add_argument("--native", default="lmp")
    ap.add_argument("--var", nargs=2, action="append", default=[], metavar=("NAME", "VALUE"))
    ap.add_argument("--only", choices=("fibre", "native"), help="run one twin only")
    args = ap.parse_args()
    args.lmp = os.path.abspath(args.lmp)
    if args.command == "run":
        run(args)
    else:
        report(args)


if __name__ == "__main__":
    sys.exit(main())
