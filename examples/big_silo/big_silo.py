#!/usr/bin/env python3
"""The production-sized silo (in.big_silo): fix fibre_contact and its native twin run one after
the other on the same spheres, walls and pair_coeff, and their figures side by side: the
settled bed (highest sphere, centre of mass), the discharge rate (a line fitted to the spheres
above the floor from tskip after opening to the end), the spheres left, the seconds of the runs'
loops (and per simulated second), the largest resident set (GNU time) and the pictures (a slice
through the orifice's axis, coloured by speed).

  python3 examples/big_silo/big_silo.py [--lmp build/fix/lmp_fibre] [--R 30 --H 72]
                                        [--workdir W] [--methods fibre native] [--np 1]
"""

import argparse
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools"))
from lammps_runs import (MAX_RSS_PREFIX, least_squares_slope, lmp_env,  # noqa: E402
                         max_rss_kib, mpi_prefix, parse_thermo)


def run(lmp, method, workdir, np=1, R=30, H=72, Do=8.0, tsettle=4.0, tflow=1.5, tskip=0.4):
    """One twin's run in workdir; its figures (a dict), or None where it failed."""
    os.makedirs(workdir, exist_ok=True)
    log = os.path.join(workdir, "log.big_silo.%s" % method)
    cmd = mpi_prefix("mpirun", np) + MAX_RSS_PREFIX + [
        lmp, "-in", os.path.join(HERE, "in.big_silo"), "-log", log, "-echo", "none",
        "-var", "method", method, "-var", "R", "%g" % R, "-var", "H", "%g" % H,
        "-var", "Do", "%g" % Do, "-var", "tsettle", "%g" % tsettle, "-var", "tflow", "%g" % tflow]
    proc = subprocess.run(cmd, cwd=workdir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          env=lmp_env())
    out = proc.stdout.decode("utf-8", "replace")
    if proc.returncode != 0:
        print("big_silo: %s failed (rc %d): %s" % (method, proc.returncode, out[-600:]))
        return None
    text = open(log).read()
    settle, flow = parse_thermo(text)[-2:]
    t_open = flow[0]["Time"]
    window = [r for r in flow if r["Time"] >= t_open + tskip]
    settled = re.search(r"BIGSILO settled zmax (\S+) zcm (\S+)", text)
    loops = [float(x) for x in re.findall(r"Loop time of (\S+)", text)]
    figures = {
        "spheres": int(settle[0]["Atoms"]), "settled": int(settle[-1]["Atoms"]),
        "left": int(flow[-1]["Atoms"]),
        "inside": int(flow[-1]["v_inside"]), "zmax": float(settled.group(1)),
        "zcm": float(settled.group(2)),
        "rate": -least_squares_slope([r["Time"] for r in window],
                                     [r["v_inside"] for r in window]),
        "loop": sum(loops), "sim": flow[-1]["Time"],
        "rss": max_rss_kib(out) / 1024.0}
    if method == "fibre":
        figures["contacts"] = int(flow[-1]["f_fc[3]"])
        figures["sweeps"] = max(int(r["f_fc[14]"]) for r in settle + flow)
        figures["overlap"] = max(r["f_fc[7]"] for r in flow)
    return figures


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--lmp", default=os.path.join(HERE, "..", "..", "build", "fix", "lmp_fibre"))
    p.add_argument("--R", type=float, default=30, help="the bin's radius")
    p.add_argument("--H", type=float, default=72, help="the top of the fill")
    p.add_argument("--Do", type=float, default=8.0, help="the orifice's diameter")
    p.add_argument("--tsettle", type=float, default=4.0)
    p.add_argument("--tflow", type=float, default=1.5)
    p.add_argument("--tskip", type=float, default=0.4, help="the rate's fit starts this late")
    p.add_argument("--np", type=int, default=1)
    p.add_argument("--methods", nargs="+", default=["fibre", "native"])
    p.add_argument("--workdir", default="big-silo-runs")
    args = p.parse_args()
    args.lmp = os.path.abspath(args.lmp)
    os.makedirs(args.workdir, exist_ok=True)
    results = {}
    for m in args.methods:
        results[m] = run(args.lmp, m, args.workdir, args.np, args.R, args.H, args.Do,
                         args.tsettle, args.tflow, args.tskip)
        if results[m] is None:
            sys.exit(1)
    rows = [("spheres", "%d", "spheres"), ("settled: highest sphere (m)", "%.3f", "zmax"),
            ("settled: centre of mass (m)", "%.3f", "zcm"),
            ("discharge rate (spheres / s, fitted)", "%.1f", "rate"),
            ("spheres above the floor at the end", "%d", "inside"),
            ("wall seconds (the runs' loops)", "%.0f", "loop"),
            ("wall seconds per simulated second", "%.0f", None), ("max RSS (MB)", "%.0f", "rss")]
    print("| figure | " + " | ".join(args.methods) + " |")
    print("|---" * (len(args.methods) + 1) + "|")
    for name, fmt, key in rows:
        cells = []
        for m in args.methods:
            r = results[m]
            cells.append(fmt % (r["loop"] / r["sim"] if key is None else r[key]))
        print("| %s | %s |" % (name, " | ".join(cells)))
    if "fibre" in results:
        f = results["fibre"]
        print("fix: %d contacts at the end, at most %d sweeps a step, deepest overlap of the "
              "discharge %.3f" % (f["contacts"], f["sweeps"], f["overlap"]))
    if "fibre" in results and "native" in results:
        f, n = results["fibre"], results["native"]
        print("native / fix speed %.2fx; rate %+.1f%%; RSS fix / native %.2f" % (
            n["loop"] / f["loop"], 100.0 * (f["rate"] / n["rate"] - 1.0), f["rss"] / n["rss"]))


if __name__ == "__main__":
    main()
