#!/usr/bin/python3
"""Read LIGGGHTS logs of the hopper and mixer scenes and report their figures as markdown.

    compare.py report LOG [LOG...]   hopper: steady discharge rate, wall time; one row per log
    compare.py mixer  LOG [LOG...]   mixer: mean kinetic energy, torque and power of the blade
                                     over the rotation phase, lost spheres, wall time
    compare.py heap   DUMP [DUMP...] heap: angle of repose and height from the final dump
                                     (id x y z radius) of the heap scene

LOG is a LIGGGHTS log (log.liggghts or the file given to -log). Options:
    --plot FILE.png   also plot the logs (hopper: spheres in the hopper against the time since
                      the opening, with the fitted lines; mixer: kinetic energy and torque)
    --lo F --hi F     (report) the discharge window: from fraction F_lo to F_hi of the spheres
                      in the hopper at the opening discharged (default 0.2 .. 0.8)

What is read (the thermo columns that run.hopper / run.mixer print; v_/c_/f_ prefixes are
optional): Step, Time, Atoms; hopper: nin (spheres above the orifice plane), min (their mass);
mixer: KinEng + rke (or ektot), tz (torque on the blade), power, nout (spheres outside the
drum). The run blocks are split at the `Loop time of T on P procs for M steps` lines. The
hopper's discharge starts with its last run block (the run after `open_orifice`); the mixer's
rotation phase is its last run block.

Wall seconds per simulated second: the sum of the blocks' Loop times over the sum of their
simulated times (steps x dt, dt from the thermo Time and Step columns), for the whole run and
for the last block alone; for the hopper also over the discharge window, from the thermo cpu
column (wall seconds since the run began) where the log has it. Only the standard library, numpy and matplotlib are used.
"""
import argparse
import math
import os
import re
import sys

import numpy as np

LOOP = re.compile(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms")
OMEGA = re.compile(r"omega = ([0-9.eE+-]+) rad/s")


class Block:
    """One `run`: its thermo table and its Loop time line."""

    def __init__(self, names):
        self.names = names
        self.rows = []
        self.loop = None      # wall seconds
        self.procs = None
        self.steps = None

    def col(self, *names):
        for n in names:
            if n in self.names:
                return np.array([r[self.names.index(n)] for r in self.rows])
        raise KeyError("none of the thermo columns %s in the log (have: %s)"
                       % (", ".join(names), " ".join(self.names)))

    def has(self, name):
        return name in self.names

    def dt(self):
        s, t = self.col("Step"), self.col("Time")
        if len(s) < 2 or s[-1] == s[0]:
            return None
        return (t[-1] - t[0]) / (s[-1] - s[0])

    def simulated(self):
        dt = self.dt()
        return None if dt is None or self.steps is None else self.steps * dt


def strip(name):
    for p in ("v_", "c_", "f_"):
        if name.startswith(p):
            return name[len(p):]
    return name


def parse(path):
    """Run blocks of a LIGGGHTS log, and the printed blade angular velocity if any."""
    blocks, cur, omega = [], None, None
    with open(path, errors="replace") as f:
        for line in f:
            tok = line.split()
            m = LOOP.search(line)
            if m:
                if cur is not None:
                    cur.loop, cur.procs, cur.steps = float(m.group(1)), int(m.group(2)), int(m.group(3))
                    blocks.append(cur)
                cur = None
                continue
            m = OMEGA.search(line)
            if m and line.startswith("MIXER"):
                omega = float(m.group(1))
            if tok and tok[0] == "Step" and cur is None:
                cur = Block([strip(t) for t in tok])
                continue
            if cur is not None and len(tok) == len(cur.names):
                try:
                    cur.rows.append([float(t) for t in tok])
                except ValueError:
                    pass            # INFO lines and the like inside the table
    if cur is not None and cur.rows:  # a run cut short: no Loop time line
        blocks.append(cur)
    blocks = [b for b in blocks if b.rows]
    if not blocks:
        raise SystemExit("%s: no thermo output found" % path)
    return blocks, omega


def joined(blocks, *names):
    """A column over all blocks, the repeated first row of each later block left out."""
    out, last = [], None
    for b in blocks:
        s, c = b.col("Step"), b.col(*names)
        for si, ci in zip(s, c):
            if last is None or si > last:
                out.append(ci)
                last = si
    return np.array(out)


def timing(blocks):
    """(wall s, simulated s, wall per simulated s) of all blocks and of the last block."""
    done = [b for b in blocks if b.loop is not None and b.simulated()]
    wall = sum(b.loop for b in done)
    sim = sum(b.simulated() for b in done)
    last = blocks[-1]
    lw = last.loop / last.simulated() if last.loop is not None and last.simulated() else float("nan")
    return wall, sim, (wall / sim if sim else float("nan")), lw


def fit(t, y):
    """Slope, intercept and R^2 of a straight line fitted to y(t)."""
    if len(t) < 3:
        return float("nan"), float("nan"), float("nan")
    b, a = np.polyfit(t, y, 1)
    res = y - (a + b * t)
    ss = np.sum((y - y.mean()) ** 2)
    return b, a, (1.0 - np.sum(res ** 2) / ss if ss > 0 else float("nan"))


def hopper(path, lo, hi):
    blocks, _ = parse(path)
    if len(blocks) < 2:
        raise SystemExit("%s: expected a fill run and a discharge run" % path)
    dis = blocks[-1]
    t, n, m = dis.col("Time"), dis.col("nin"), dis.col("min")
    t_open, n0, m0 = t[0], n[0], m[0]
    frac = (n0 - n) / n0 if n0 > 0 else np.zeros_like(n)
    sel = (frac >= lo) & (frac <= hi)
    rate_n, _, r2 = fit(t[sel], n[sel])
    rate_m, _, _ = fit(t[sel], m[sel])
    empty = t[n <= 0]
    wall, sim, wps, wps_last = timing(blocks)
    wps_win = float("nan")
    if (dis.has("cpu") or dis.has("CPU")) and sel.sum() >= 2:       # thermo cpu: wall seconds since the run began
        c, tw = dis.col("cpu", "CPU")[sel], t[sel]
        wps_win = (c[-1] - c[0]) / (tw[-1] - tw[0])
    inserted = int(max(joined(blocks, "Atoms")))
    return {
        "log": path, "procs": dis.procs, "inserted": inserted, "n0": int(n0), "m0": m0,
        "t_open": t_open, "dt": dis.dt(),
        "t_lo": t[sel][0] - t_open if sel.any() else float("nan"),
        "t_hi": t[sel][-1] - t_open if sel.any() else float("nan"),
        "points": int(sel.sum()), "rate_n": -rate_n, "rate_m": -rate_m, "r2": r2,
        "t_empty": (empty[0] - t_open) if len(empty) else float("nan"),
        "left": int(n[-1]), "wall": wall, "sim": sim, "wps": wps, "wps_last": wps_last,
        "wps_win": wps_win, "series": (t - t_open, n),
    }


def mixer(path):
    blocks, omega = parse(path)
    rot = blocks[-1]
    t = rot.col("Time")[1:]
    if rot.has("ektot"):
        ek = rot.col("ektot")[1:]
    else:
        ek = rot.col("KinEng")[1:] + rot.col("rke")[1:]
    tz = rot.col("tz")[1:]
    pw = rot.col("power")[1:]
    last = t >= t[-1] - 2 * math.pi / omega + 1e-9 if omega else np.ones_like(t, bool)
    atoms = joined(blocks, "Atoms")
    atoms_in = atoms[atoms > 0]
    nout = joined(blocks, "nout")
    wall, sim, wps, wps_last = timing(blocks)
    allt, allek = joined(blocks, "Time"), (joined(blocks, "ektot") if rot.has("ektot") else
                                          joined(blocks, "KinEng") + joined(blocks, "rke"))
    return {
        "log": path, "procs": rot.procs, "omega": omega, "t_rot": rot.col("Time")[0],
        "t_end": t[-1], "revs": (t[-1] - rot.col("Time")[0]) * omega / (2 * math.pi) if omega else float("nan"),
        "ke": ek.mean(), "ke_last": ek[last].mean(), "ke_max": ek.max(),
        "tz": tz.mean(), "tz_last": tz[last].mean(), "pw": pw.mean(), "pw_last": pw[last].mean(),
        "atoms_max": int(atoms_in.max()), "atoms_min": int(atoms_in.min()),
        "atoms_end": int(atoms[-1]), "nout_max": int(nout.max()),
        "wall": wall, "sim": sim, "wps": wps, "wps_last": wps_last,
        "series": (allt, allek, joined(blocks, "Time"), joined(blocks, "tz")),
    }


def heap(path, plate=0.05, bin_width=0.0025, lo=0.2, hi=0.8):
    """The heap's surface from a dump: in radial bins of bin_width over the plate, the highest
    sphere top (z + radius); the height H is the highest top. Two angles of repose: the
    fixed-base angle atan(H / plate) of a heap that spills over the plate's rim, and the slope
    of a straight line fitted to the tops of the bins between lo H and hi H."""
    with open(path) as f:
        lines = f.read().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith("ITEM: ATOMS"))
    names = lines[i].split()[2:]
    rows = [[float(w) for w in ln.split()] for ln in lines[i + 1:] if ln.strip()]
    a = np.array(rows)
    x, y, z, r = (a[:, names.index(n)] for n in ("x", "y", "z", "radius"))
    rad = np.hypot(x, y)
    on = (rad < plate) & (z > -0.001)
    tops = []
    for b in range(int(plate / bin_width)):
        sel = on & (rad >= b * bin_width) & (rad < (b + 1) * bin_width)
        if sel.any():
            tops.append(((b + 0.5) * bin_width, float((z[sel] + r[sel]).max())))
    t = np.array(tops)
    height = t[:, 1].max()
    flank = (t[:, 1] >= lo * height) & (t[:, 1] <= hi * height)
    slope, _, r2 = fit(t[flank, 0], t[flank, 1])
    return {"dump": path, "spheres": int(on.sum()), "height": height,
            "angle": math.degrees(math.atan(-slope)), "r2": r2, "bins": int(flank.sum()),
            "fixed_base": math.degrees(math.atan(height / plate))}


def cmd_heap(a):
    rows = []
    for path in a.dumps:
        h = heap(path)
        rows.append([h["dump"], str(h["spheres"]), g(1000 * h["height"], "%.1f"),
                     g(h["fixed_base"], "%.1f"), g(h["angle"], "%.1f"), str(h["bins"]),
                     g(h["r2"], "%.3f")])
    print(table(["dump", "spheres on the plate", "height H (mm)",
                 "angle atan(H / R_plate) (deg)", "flank fit angle (deg)", "flank bins",
                 "flank R^2"], rows))
    return 0


def g(x, fmt="%.4g"):
    return "" if x is None or (isinstance(x, float) and math.isnan(x)) else fmt % x


def table(head, rows):
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(out)


def cmd_report(a):
    res = [hopper(p, a.lo, a.hi) for p in a.logs]
    head = ["log", "procs", "spheres at opening", "mass at opening (kg)", "dt (s)",
            "window (s after opening)", "points", "rate (particles/s)", "rate (kg/s)",
            "R^2", "empty after (s)", "left", "simulated (s)", "wall (s)",
            "wall s per simulated s", "discharge run", "discharge window"]
    rows = [[r["log"], str(r["procs"]), str(r["n0"]), g(r["m0"]), g(r["dt"]),
             "%s .. %s" % (g(r["t_lo"], "%.3f"), g(r["t_hi"], "%.3f")), str(r["points"]),
             g(r["rate_n"], "%.1f"), g(r["rate_m"], "%.4f"), g(r["r2"], "%.4f"),
             g(r["t_empty"], "%.3f"), str(r["left"]), g(r["sim"], "%.3f"), g(r["wall"], "%.1f"),
             g(r["wps"], "%.2f"), g(r["wps_last"], "%.2f"), g(r["wps_win"], "%.2f")]
            for r in res]
    print("Hopper discharge, window: %g%% .. %g%% of the spheres at the opening discharged.\n"
          "Wall s per simulated s: whole log and discharge run from the Loop time lines, "
          "discharge window from the thermo cpu column.\n" % (100 * a.lo, 100 * a.hi))
    print(table(head, rows))
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(6, 4))
        for r in res:
            t, n = r["series"]
            ax.plot(t, n, label="%s (%.0f /s)" % (os.path.basename(r["log"]), r["rate_n"]))
        ax.set_xlabel("time since opening (s)")
        ax.set_ylabel("spheres above the orifice")
        ax.legend()
        fig.tight_layout()
        fig.savefig(a.plot, dpi=120)
        print("\nplot: %s" % a.plot)


def cmd_mixer(a):
    res = [mixer(p) for p in a.logs]
    head = ["log", "procs", "omega (rad/s)", "revolutions", "mean KE, rotation (J)",
            "mean KE, last rev (J)", "max KE (J)", "mean torque tz, rotation (N m)",
            "mean torque, last rev (N m)", "mean power, rotation (W)", "atoms (min..max)",
            "atoms at end", "max outside the drum", "simulated (s)", "wall (s)",
            "wall s per simulated s", "rotation phase: wall s per simulated s"]
    rows = [[r["log"], str(r["procs"]), g(r["omega"]), g(r["revs"], "%.2f"), g(r["ke"]),
             g(r["ke_last"]), g(r["ke_max"]), g(r["tz"]), g(r["tz_last"]), g(r["pw"]),
             "%d..%d" % (r["atoms_min"], r["atoms_max"]), str(r["atoms_end"]),
             str(r["nout_max"]), g(r["sim"], "%.3f"), g(r["wall"], "%.1f"), g(r["wps"], "%.2f"),
             g(r["wps_last"], "%.2f")] for r in res]
    print("Mixer: kinetic energy (translational + rotational) and blade torque over the "
          "rotation phase\n")
    print(table(head, rows))
    lost = [r["log"] for r in res if r["atoms_min"] != r["atoms_max"] or r["nout_max"] > 0]
    print("\nspheres lost or outside the drum: %s" % (", ".join(lost) if lost else "none"))
    if a.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(6, 6), sharex=True)
        for r in res:
            t, ek, tt, tz = r["series"]
            lab = os.path.basename(r["log"])
            ax1.plot(t, ek, label=lab)
            ax2.plot(tt, tz, label=lab)
        ax1.set_ylabel("kinetic energy (J)")
        ax2.set_ylabel("torque on the blade, z (N m)")
        ax2.set_xlabel("time (s)")
        ax1.legend()
        fig.tight_layout()
        fig.savefig(a.plot, dpi=120)
        print("\nplot: %s" % a.plot)
    return 1 if lost else 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("report", help="hopper discharge rate and wall time, one row per log")
    p.add_argument("logs", nargs="+")
    p.add_argument("--lo", type=float, default=0.2)
    p.add_argument("--hi", type=float, default=0.8)
    p.add_argument("--plot")
    p.set_defaults(func=cmd_report)
    p = sub.add_parser("mixer", help="mixer kinetic energy, torque, lost spheres, wall time")
    p.add_argument("logs", nargs="+")
    p.add_argument("--plot")
    p.set_defaults(func=cmd_mixer)
    p = sub.add_parser("heap", help="heap angle of repose and height from final dumps")
    p.add_argument("dumps", nargs="+")
    p.set_defaults(func=cmd_heap)
    a = ap.parse_args(argv)
    return a.func(a) or 0


if __name__ == "__main__":
    sys.exit(main())
