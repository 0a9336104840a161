#!/usr/bin/env python3
"""The scale benchmark: fix fibre_contact against native LAMMPS on a dense bed that grows
(bench/scale/in.bed: D fcc cells deep, W across, N = 4 W^2 D spheres settling for tend
simulated seconds; growing in width at a fixed depth, or with --width in depth), both twins of
one size and process count run back to back: the fix at its default step 0.002 s, native at
t_c / 20 (the Hertz collision time of the smallest spheres at 1 m/s), the step at which its
bed agrees with a step 100 times smaller.

For each run: wall seconds per simulated second, the largest resident set of any process
(GNU time), bytes per sphere and per contact above the same method's run of 16 spheres (of the
largest process, over its share of them; the
fix's contacts at the end, walls included; native's pair contacts from compute contact/atom),
the fix's sweeps and error estimate of the
last step, with --check its last check's velocity error against the converged step, and the
sweeps' cost per contact-sweep over the run (a process's sweep seconds over its share of the
contacts times the sweeps, summed over the steps). The speed ratio is native's wall time over
the fix's for the same simulated time.

  python3 bench/scale.py [--lmp build/fix/lmp_fibre] [--N 10000 100000] [--np 1 2]
                         [--depth 10 | --width W] [--tend 0.5] [--E 1e7] [--L 1]
                         [--dt-fibre 0.002] [--keywords "..."] [--check] [--workdir W]
                         [--methods ...]
"""

import argparse
import math
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tools"))
from lammps_runs import MAX_RSS_PREFIX, lmp_env, max_rss_kib, mpi_prefix, parse_thermo  # noqa: E402


def collision_time(E, L=1.0, nu=0.3, density=2500.0, v=1.0):
    """The Hertz collision time of two of the bed's smallest spheres (radius 0.45 L) meeting at
    v, by the fix's formula (fibre::collision_time) with LAMMPS's hertz/material pair constant
    k_n = 4/3 E / (2 (1 - nu^2)); the fix's log names the shortest over its type pairs, which
    may be a wall's."""
    r = 0.45 * L
    m = density * 4.0 / 3.0 * math.pi * r ** 3
    K = 4.0 / 3.0 * E / (2.0 * (1.0 - nu * nu)) * math.sqrt(0.5 * r)
    d_max = (1.25 * 0.5 * m * v * v / K) ** 0.4
    half = 0.4 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)
    return 2.0 * half * d_max / v


def native_step(E, L=1.0):
    """Native's step: t_c / 20 at 1 m/s."""
    return collision_time(E, L) / 20.0


def run(lmp, np, method, W, D, tend, check, workdir, E=1e7, L=1.0, dt_fibre=0.002, keywords=""):
    """One run; its figures (a dict) or None where it failed."""
    os.makedirs(workdir, exist_ok=True)
    log = os.path.join(workdir, "log.%s.W%d.np%d" % (method, W, np))
    steps = round(tend / dt_fibre)
    cmd = mpi_prefix("mpirun", np) + MAX_RSS_PREFIX + [
        lmp, "-in", os.path.join(HERE, "scale", "in.bed"),
        "-log", log, "-echo", "none", "-var", "W", str(W), "-var", "D", str(D),
        "-var", "method", method, "-var", "tend", str(tend), "-var", "E", "%g" % E,
        "-var", "L", "%g" % L, "-var", "dt_fibre", "%g" % dt_fibre, "-var", "fc_extra", keywords,
        "-var", "dt_native", "%.3g" % native_step(E, L),
        "-var", "check", str(steps if check else 0)]
    t0 = time.time()
    proc = subprocess.run(cmd, cwd=workdir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          env=lmp_env())
    wall = time.time() - t0
    out = proc.stdout.decode("utf-8", "replace")
    if proc.returncode != 0:
        print("  %s np %d W %d failed (rc %d): %s" % (method, np, W, proc.returncode,
                                                      out[-400:]))
        return None
    text = open(log).read()
    rows = parse_thermo(text)[-1]
    last = rows[-1]
    loop = float(re.search(r"Loop time of (\S+)", text).group(1))
    rss = max_rss_kib(out) * 1024
    atoms = int(last["Atoms"])
    if method == "fibre":
        contacts = last["f_fc[3]"]
        extra = {"sweeps": last["f_fc[14]"], "estimate": last["f_fc[16]"],
                 "check": last["f_fc[19]"] if check else None}
        cost = re.search(r"^SCALE sweep_seconds (\S+) contact_sweeps (\S+)", text, re.M)
        if cost and float(cost.group(2)) > 0:  # a process's sweep time per contact-sweep
            extra["sweep_ns"] = 1e9 * float(cost.group(1)) * np / float(cost.group(2))
    else:
        contacts = last["c_csum"] / 2.0
        extra = {}
    zc = re.search(r"^SCALE atoms \S+ zc (\S+)", text, re.M)
    fig = {"atoms": atoms, "contacts": contacts, "loop": loop, "wall": wall,
           "per_second": loop / tend, "rss": rss, "zc": float(zc.group(1)) if zc else None}
    fig.update(extra)
    return fig


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--lmp", default=os.path.join(HERE, "..", "build", "fix", "lmp_fibre"))
    p.add_argument("--N", type=int, nargs="+", default=[10000, 100000])
    p.add_argument("--np", type=int, nargs="+", default=[1, 2])
    p.add_argument("--depth", type=int, default=10)
    p.add_argument("--width", type=int, default=0,
                   help="fcc cells across, fixed: the bed grows in depth (0: it grows in width)")
    p.add_argument("--tend", type=float, default=0.5)
    p.add_argument("--E", type=float, default=1e7, help="Young's modulus, spheres and walls")
    p.add_argument("--L", type=float, default=1.0,
                   help="length unit: 1, spheres a metre across; 1e-3, beads of a millimetre")
    p.add_argument("--dt-fibre", type=float, default=0.002, help="the fix's step")
    p.add_argument("--keywords", default="", help="more fix fibre_contact keywords")
    p.add_argument("--check", action="store_true", help="check the last step of the fix")
    p.add_argument("--methods", nargs="+", default=["fibre", "native"])
    p.add_argument("--workdir", default="scale-runs")
    a = p.parse_args()
    lmp = os.path.abspath(a.lmp)
    print("E %g, L %g: the fix at %g s%s, native at t_c / 20 = %.3g s (t_c %.3g s at 1 m/s)"
          % (a.E, a.L, a.dt_fibre, (" with '%s'" % a.keywords) if a.keywords else "",
             native_step(a.E, a.L), collision_time(a.E, a.L)))
    extra = (a.E, a.L, a.dt_fibre, a.keywords)
    print("| N | np | contacts | fix s / sim s | native s / sim s | native / fix speed | "
          "RSS fix | RSS native | fix bytes / sphere, / contact | "
          "native bytes / sphere, / contact | "
          "sweeps | estimate | check | ns / contact-sweep |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    base = {}  # the resident set of a run of 16 spheres, per method and process count
    for np in a.np:
        for m in a.methods:
            small = run(lmp, np, m, 2, 1, 0.01, False,
                        os.path.join(os.path.abspath(a.workdir), "base"), *extra)
            base[m, np] = small["rss"] if small else 0
    for n in a.N:
        if a.width:
            W, D = a.width, max(1, round(n / (4.0 * a.width ** 2)))
        else:
            W, D = max(2, round((n / (4.0 * a.depth)) ** 0.5)), a.depth
        for np in a.np:
            figs = {m: run(lmp, np, m, W, D, a.tend, a.check,
                           os.path.join(os.path.abspath(a.workdir), "W%dD%d" % (W, D)), *extra)
                    for m in a.methods}
            for m, d in figs.items():
                if d:
                    # the largest process's: its share of the spheres and contacts
                    d["per_sphere"] = (d["rss"] - base[m, np]) * np / d["atoms"]
                    d["per_contact"] = (d["rss"] - base[m, np]) * np / max(d["contacts"], 1.0)
            f, nat = figs.get("fibre"), figs.get("native")
            cell = lambda d, k, fmt, s=1.0: fmt % (s * d[k]) if d and d.get(k) is not None else "-"  # noqa
            ratio = "%.2fx" % (nat["loop"] / f["loop"]) if f and nat else "-"
            atoms = (f or nat or {}).get("atoms", 0)
            print("| %d | %d | %s | %s | %s | %s | %s | %s | %s, %s | %s, %s | %s | %s | %s | %s |" % (
                atoms, np, cell(f, "contacts", "%.0f"), cell(f, "per_second", "%.1f"),
                cell(nat, "per_second", "%.1f"), ratio,
                cell(f, "rss", "%.0f MB", 1e-6), cell(nat, "rss", "%.0f MB", 1e-6),
                cell(f, "per_sphere", "%.0f"), cell(f, "per_contact", "%.0f"),
                cell(nat, "per_sphere", "%.0f"), cell(nat, "per_contact", "%.0f"),
                cell(f, "sweeps", "%.0f"),
                cell(f, "estimate", "%.2g"), cell(f, "check", "%.2g"),
                cell(f, "sweep_ns", "%.1f")), flush=True)


if __name__ == "__main__":
    main()
