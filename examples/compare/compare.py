#!/usr/bin/python3
"""Compare fix fibre_contact with its native LAMMPS twin on the silo and material scenes.

Subcommands (run from anywhere; paths default to this repository):

  compare.py run SCENE --N N [--method fibre|native|both] [--np P] [--var NAME VALUE ...]
      copies the scene's decks into WORKDIR/SCENE.N (default /tmp/scenes/compare) and runs
      them: lmp_fibre on in.SCENE, Debian's lmp on in.SCENE.native. Logs are named
      log.SCENE.METHOD.N (with --tag T: log.SCENE.METHOD.N.T).
  compare.py report SCENE --N N [--out DIR]
      reads both twins' logs and dumps and writes DIR/SCENE.N.md (a markdown table) and the
      PNG plots DIR/SCENE.N.*.png; prints the table.
  compare.py beverloo --N N --D D1 D2 ... [--run] [--out DIR]
      silo runs at several orifice diameters (with --run: runs the missing ones), the steady
      discharge rate of each, and the fit of Beverloo's law W = C rho_b sqrt(g) (D - k d)^2.5
      for each method.
  compare.py seeds SCENE --N N --seeds S1 S2 ... [--run] [--jobs J] [--tag T]
                 [--var NAME VALUE] [--fibre-var NAME VALUE] [--native-var NAME VALUE]
                 [--native-tag T0] [--against-tag T1] [--from-table FILE]
      both twins over several seeds of fix pour (one run directory per seed,
      WORKDIR/SCENE.N.T_sSEED; with --run: runs what is missing, J runs at a time), and per
      twin the mean, range and standard deviation of the heap's height and angle (material) or
      the discharge rate (silo, flowing seeds only), the wall seconds per simulated second,
      and the fix's difference from native, paired by seed and between the twins' own means,
      each with its standard error; writes
      DIR/SCENE.N.seeds.T.md and prints it. With --native-tag T0 the native twin is read
      from (or run in) the directories of tag T0, so that several settings of the fix are
      set against one set of native runs. With --against-tag T1 the fix's runs are also
      paired by seed with the fix's runs of tag T1 (another setting of the fix, the same
      seeds), and the table gains their difference. With --from-table FILE (a former seeds
      table of this scene) native's figures are that table's and only the fix runs: a rerun
      of the fix against native runs kept from an earlier run; the table gains the fix's
      difference from the former table's fix, and its speed line is left out (the twins'
      wall seconds are then of different machines).
  compare.py picture SCENE --N N [--method M] [--when last|filled|STEP] [--out DIR]
      a PNG snapshot of a run's dump (LAMMPS dump image, coloured by height), for the README.

What is measured (the same code for both methods, from the thermo output and the dumps):

  silo      mass in the box over time (thermo v_mass; spheres that leave through the orifice
            fall out of the box and are removed); the discharge rate W(t) = -dm/dt over
            windows of 0.5 s; the steady rate: slope of a straight-line fit of m(t) from 1 s
            after opening until 40% of the mass at opening has left (before the funnel runs
            empty), or until the end of the run. A flow that stops with mass left is a clog:
            in the last 1.5 s less than a tenth of the mass left than in the 1.5 s after the
            fit starts (an arch that lets a sphere through now and then is still a clog).
  material  pile height: the highest sphere top (z + r) of the final dump; angle of repose:
            the surface of the pile is the highest sphere top in radial bins of width 1 (the
            largest diameter) around the pile's centre, in four azimuthal quadrants; on each
            quadrant a straight line is fitted to the flank, the bins whose surface lies
            between 20% and 80% of the pile height (this leaves out the flat top under the
            emitter and the toe of single spheres); the angle is atan(-slope), reported as
            the mean of the quadrants and their standard deviation.
  both      kinetic energy (translational c_ke + rotational c_rot) over time; maximum
            overlap: the deepest sphere-sphere overlap (r_i + r_j - |x_i - x_j|) and, for the
            material's floor, sphere-plane overlap (r - z), over all snapshots of the run (the
            trajectory dumps every simulated second and the final dump), for both methods
            alike; for fibre_contact also the fix's own max over the thermo lines (f_fc[7],
            walls included); wall-clock time (thermo 'cpu' column, summed over the runs) per
            simulated second.

Needs numpy and matplotlib (Debian: python3-numpy, python3-matplotlib; use /usr/bin/python3).
"""

import argparse
import glob
import math
import os
import shutil
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "tools"))
import lammps_runs  # noqa: E402  (tools/lammps_runs.py: shared with tests/e2e/fibre_e2e.py)
DEFAULT_WORK = "/tmp/scenes/compare"
PILE_SCENES = ("material", "silo")  # the drum has its own tool, drum.py
DEFAULT_OUT = os.path.join(HERE, "results")
METHODS = ("native", "fibre")
COLORS = {"native": "tab:blue", "fibre": "tab:red"}
LABELS = {"native": "native (Hertz-Mindlin, nve/sphere)", "fibre": "fix fibre_contact"}
RHO = 1.0          # sphere density of both scenes
G = 9.81


def die(msg):
    sys.exit("compare.py: error: " + msg)


# ----------------------------------------------------------------------------- parsing

def parse_thermo(path):
    """Thermo blocks of a LAMMPS log: list (one per run) of dicts column -> numpy array."""
    if not os.path.exists(path):
        die("no log file %s (run it first: compare.py run ...)" % path)
    out = []
    for header, rows in lammps_runs.thermo_blocks(lammps_runs.read_text(path)):
        if rows:
            a = np.array(rows)
            out.append({h: a[:, k] for k, h in enumerate(header)})
    if not out:
        die("no thermo output in %s" % path)
    return out


def log_value(path, prefix):
    """Words of the last log line that starts with prefix (or None)."""
    return lammps_runs.last_line_words(lammps_runs.read_text(path), prefix)


def read_frames(path):
    """All frames of a LAMMPS custom dump: list of (step, dict column -> array)."""
    frames = []
    for step, cols, rows in lammps_runs.parse_dump(path):
        a = np.array(rows, dtype=float).reshape(len(rows), len(cols))
        frames.append((step, {c: a[:, k] for k, c in enumerate(cols)}))
    return frames


def max_pair_overlap(x, r):
    """Deepest overlap r_i + r_j - |x_i - x_j| over all pairs (0 if none), in row chunks."""
    n = len(r)
    worst = 0.0
    for lo in range(0, n, 400):
        hi = min(n, lo + 400)
        d = np.sqrt(((x[lo:hi, None, :] - x[None, :, :]) ** 2).sum(axis=2))
        ov = r[lo:hi, None] + r[None, :] - d
        idx = np.arange(lo, hi)
        ov[idx - lo, idx] = -np.inf
        worst = max(worst, float(ov.max()))
    return max(worst, 0.0)


# ----------------------------------------------------------------------------- running

def log_name(scene, method, n, tag=None):
    return "log.%s.%s.%d%s" % (scene, method, n, "." + tag if tag else "")


def run_dir(work, scene, n, tag=None):
    return os.path.join(work, "%s.%d%s" % (scene, n, "." + tag if tag else ""))


def run_one(a, scene, method, n, tag=None, variables=()):
    d = run_dir(a.workdir, scene, n, tag)
    os.makedirs(d, exist_ok=True)
    lammps_runs.copy_scene(REPO, scene, d)
    deck = "in." + scene + (".native" if method == "native" else "")
    exe = a.lmp if method == "native" else a.lmp_fibre
    cmd = lammps_runs.mpi_prefix(a.mpirun, a.np)
    cmd += ["nice", "-n", "5", exe, "-in", deck, "-log", log_name(scene, method, n, tag),
            "-screen", "none", "-var", "N", str(n)]
    for k, v in variables:
        cmd += ["-var", k, str(v)]
    env = lammps_runs.lmp_env()
    print("[%s] %s" % (d, " ".join(cmd)), flush=True)
    t0 = time.time()
    rc = subprocess.call(cmd, cwd=d, env=env)
    print("   -> rc %d, %.1f s" % (rc, time.time() - t0), flush=True)
    if rc != 0:
        die("%s failed (rc %d); see %s" % (" ".join(cmd), rc,
                                          os.path.join(d, log_name(scene, method, n, tag))))


def cmd_run(a):
    methods = METHODS if a.method == "both" else (a.method,)
    for m in methods:
        run_one(a, a.scene, m, a.N, a.tag, a.var or ())


# ----------------------------------------------------------------------------- analysis

def wall_seconds(blocks):
    return float(sum(b["CPU"][-1] for b in blocks))


def sim_seconds(blocks):
    return float(blocks[-1]["Time"][-1])


def overlaps(frames, floor):
    worst = 0.0
    for step, c in frames:
        if len(c["x"]) == 0:
            continue
        x = np.stack([c["x"], c["y"], c["z"]], axis=1)
        worst = max(worst, max_pair_overlap(x, c["radius"]))
        if floor:
            worst = max(worst, float(np.max(c["radius"] - c["z"])))
    return worst


def dump_frames(d, pattern):
    frames = []
    for p in sorted(glob.glob(os.path.join(d, pattern))):
        frames += read_frames(p)
    return frames


def silo_flow(blocks):
    """Mass in the box during the discharge run (the last thermo block)."""
    b = blocks[-1]
    return b["Time"], b["v_mass"]


def steady_rate(t, m):
    """(rate, t0, t1, clogged) of a discharge curve m(t), opened at t[0]."""
    t0 = t[0] + 1.0
    m0 = m[0]
    gone = m0 - m
    sel = (t >= t0) & (gone <= 0.4 * m0)
    if sel.sum() < 5:
        return float("nan"), t0, t0, False
    ts, ms = t[sel], m[sel]
    slope = np.polyfit(ts, ms, 1)[0]
    # a clog: with mass left, the last 1.5 s let out less than a tenth of what the first
    # 1.5 s of the fit did (a sphere through an arch now and then is still a clog)
    late = t >= t[-1] - 1.5
    early = (t >= t0) & (t <= t0 + 1.5)
    late_out = m[late][0] - m[-1]
    early_out = m[early][0] - m[early][-1] if early.sum() >= 2 else 0.0
    clogged = bool(m[-1] > 0.05 * m0 and late_out < 0.1 * max(early_out, 0.0) + 1e-12)
    return -float(slope), float(ts[0]), float(ts[-1]), clogged


def windowed_rate(t, m, width=0.5):
    tc, w = [], []
    k = 0
    while k < len(t):
        j = np.searchsorted(t, t[k] + width)
        if j >= len(t):
            break
        tc.append(0.5 * (t[k] + t[j]))
        w.append(-(m[j] - m[k]) / (t[j] - t[k]))
        k = j
    return np.array(tc), np.array(w)


def repose(c):
    """Pile height and angle of repose (mean and spread over four quadrants) of a dump."""
    x, y, z, r = c["x"], c["y"], c["z"], c["radius"]
    top = z + r
    on = z < 3 * np.max(r) + np.max(top)  # all
    cx, cy = np.average(x[on], weights=r[on] ** 3), np.average(y[on], weights=r[on] ** 3)
    rad = np.hypot(x - cx, y - cy)
    phi = np.arctan2(y - cy, x - cx)
    height = float(np.max(top))
    angles, fits = [], []
    width = 2 * np.max(r)
    for q in range(4):
        sel = (phi >= -np.pi + q * np.pi / 2) & (phi < -np.pi + (q + 1) * np.pi / 2)
        rb, hb = [], []
        for k in range(int(np.max(rad) / width) + 1):
            s = sel & (rad >= k * width) & (rad < (k + 1) * width)
            if s.any():
                rb.append((k + 0.5) * width)
                hb.append(np.max(top[s]))
        rb, hb = np.array(rb), np.array(hb)
        flank = (hb >= 0.2 * height) & (hb <= 0.8 * height)
        if flank.sum() < 3:
            continue
        p = np.polyfit(rb[flank], hb[flank], 1)
        angles.append(math.degrees(math.atan(-p[0])))
        fits.append((rb, hb, flank, p))
    ang = float(np.mean(angles)) if angles else float("nan")
    spread = float(np.std(angles)) if len(angles) > 1 else float("nan")
    return height, ang, spread, fits, (cx, cy)


def load_method(a, scene, method, n, tag=None, history=True):
    """A run's figures; history=False leaves out those read from every snapshot (the deepest
    overlap, the angle over time), which only the report's table and plots use."""
    d = run_dir(a.workdir, scene, n, tag)
    logp = os.path.join(d, log_name(scene, method, n, tag))
    blocks = parse_thermo(logp)
    res = {"dir": d, "blocks": blocks, "wall": wall_seconds(blocks), "sim": sim_seconds(blocks)}
    res["wall_per_s"] = res["wall"] / res["sim"]
    ins = log_value(logp, "Particle insertion:")
    res["inserted_planned"] = int(ins[-4]) if ins else None
    res["atoms_end"] = int(blocks[-1]["Atoms"][-1])
    res["atoms_max"] = int(max(b["Atoms"].max() for b in blocks))
    dtv = log_value(logp, "timestep")
    res["dt"] = float(dtv[1]) if dtv else float("nan")
    if "f_fc[7]" in blocks[-1]:
        res["fc_overlap"] = float(max(b["f_fc[7]"].max() for b in blocks))
    if "f_fc[13]" in blocks[-1]:
        res["fc_compl"] = float(max(b["f_fc[13]"].max() for b in blocks))
        res["fc_iters"] = float(np.mean(np.concatenate([b["f_fc[1]"] for b in blocks])))
    if scene == "material":
        final = read_frames(os.path.join(d, "pile.%s.%d.dump" % (method, n)))[-1][1]
        res["final"] = final
        res["height"], res["angle"], res["angle_sd"], res["fits"], res["centre"] = repose(final)
        if not history:
            return res
        frames = dump_frames(d, "pile.%s.%d.traj" % (method, n)) + [(0, final)]
        res["overlap"] = overlaps(frames, floor=True)
        speed = np.sqrt(final["vx"] ** 2 + final["vy"] ** 2 + final["vz"] ** 2)
        res["median_speed"] = float(np.median(speed))
        res["moving"] = int(np.sum(speed > 0.1))
        # the angle of repose over time: every trajectory snapshot with all spheres inserted
        res["angle_t"] = []
        for step, c in frames[:-1]:
            if len(c["x"]) >= 0.99 * res["atoms_max"]:
                h, ang = repose(c)[:2]
                res["angle_t"].append((step * res["dt"], h, ang))
        diam = 2 * final["radius"]
        res["mean_d"] = float(np.mean(diam))
    else:
        t, m = silo_flow(blocks)
        res["t"], res["m"] = t, m
        res["m_open"] = float(m[0])
        res["rate"], res["fit0"], res["fit1"], res["clogged"] = steady_rate(t, m)
        res["left"] = float(m[-1])
        if not history:
            return res
        frames = dump_frames(d, "silo.%s.%d.traj" % (method, n))
        filled = os.path.join(d, "silo.%s.%d.filled.dump" % (method, n))
        if os.path.exists(filled):
            frames += read_frames(filled)
        res["overlap"] = overlaps(frames, floor=False)
        if frames:
            res["mean_d"] = float(np.mean(2 * frames[-1][1]["radius"]))
    return res


def pct(f, n):
    return 100.0 * (f - n) / n if n else float("nan")


def table(scene, n, R):
    nat, fib = R["native"], R["fibre"]
    rows = []

    def row(name, key, fmt, rel=True):
        a, b = nat.get(key), fib.get(key)
        if a is None or b is None:
            return
        diff = ("%+.1f%%" % pct(b, a)) if rel and a else ""
        rows.append("| %s | %s | %s | %s |" % (name, fmt % a, fmt % b, diff))

    row("time step dt (s)", "dt", "%.4g")
    row("spheres inserted (max atoms)", "atoms_max", "%d", rel=False)
    row("spheres at the end", "atoms_end", "%d", rel=False)
    if scene == "material":
        # The pour inserts all n spheres before the run ends; max - end alone would miss a
        # sphere lost while the count still grows.
        for r in (nat, fib):
            r["lost"] = max(r["atoms_max"], n) - r["atoms_end"]
        row("lost off the plane", "lost", "%d", rel=False)
        row("pile height, highest sphere top (m)", "height", "%.3f")
        row("angle of repose (deg, mean of 4 quadrants)", "angle", "%.1f")
        row("angle of repose, spread over quadrants (deg)", "angle_sd", "%.1f", rel=False)
        row("median sphere speed at the end (m/s)", "median_speed", "%.2g", rel=False)
        row("spheres faster than 0.1 m/s at the end", "moving", "%d", rel=False)
    else:
        row("mass at opening (kg)", "m_open", "%.2f")
        row("steady discharge rate W (kg/s)", "rate", "%.2f")
        row("mass left at the end (kg)", "left", "%.2f")
    for m in METHODS:
        R[m]["ke_end"] = float(R[m]["blocks"][-1]["c_ke"][-1] + R[m]["blocks"][-1]["c_rot"][-1])
    row("final kinetic energy, trans + rot (J)", "ke_end", "%.3g", rel=False)
    row("max overlap, all snapshots (m)", "overlap", "%.3g", rel=False)
    for m in METHODS:
        R[m]["overlap_rel"] = R[m]["overlap"] / R[m].get("mean_d", 0.75)
    row("max overlap / mean diameter", "overlap_rel", "%.2g", rel=False)
    if "fc_overlap" in fib:
        rows.append("| max overlap, f_fc[7] every thermo line (m) | - | %.3g | |" % fib["fc_overlap"])
    if "fc_compl" in fib:
        rows.append("| complementarity residual, f_fc[13], max over thermo lines | - | %.2g | |"
                    % fib["fc_compl"])
        rows.append("| Krylov iterations per step, f_fc[1], mean over thermo lines | - | %.0f | |"
                    % fib["fc_iters"])
    row("simulated time (s)", "sim", "%.2f", rel=False)
    row("wall-clock time (s)", "wall", "%.1f", rel=False)
    row("wall-clock per simulated second (s/s)", "wall_per_s", "%.2f", rel=False)
    ratio = fib["wall_per_s"] / nat["wall_per_s"]
    head = ["| %s, N = %d | native | fibre_contact | fibre vs native |" % (scene, n),
            "|---|---|---|---|"]
    tail = ["", "Wall-time ratio fibre/native: %.2f." % ratio]
    if scene == "material":
        tail.append("")
        tail.append("Pile height / angle of repose at the snapshots after the last batch:")
        tail.append("")
        tail.append("| t (s) | " + " | ".join("%s height, angle" % m for m in METHODS) + " |")
        tail.append("|---|---|---|")
        for k in range(min(len(nat["angle_t"]), len(fib["angle_t"]))):
            tail.append("| %.1f | %s |" % (nat["angle_t"][k][0], " | ".join(
                "%.2f m, %.1f deg" % R[m]["angle_t"][k][1:] for m in METHODS)))
    if scene == "silo":
        for m in METHODS:
            r = R[m]
            tail.append("%s: steady rate fitted on t = %.2f .. %.2f s%s." % (
                m, r["fit0"], r["fit1"], ", the flow CLOGGED" if r["clogged"] else ""))
    return "\n".join(head + rows + tail) + "\n"


def plots(scene, n, R, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    files = []
    fig, ax = plt.subplots(figsize=(6, 3.6))
    for m in METHODS:
        t = np.concatenate([b["Time"] for b in R[m]["blocks"]])
        ke = np.concatenate([b["c_ke"] + b["c_rot"] for b in R[m]["blocks"]])
        ax.semilogy(t, np.maximum(ke, 1e-8), color=COLORS[m], label=LABELS[m])
    ax.set_xlabel("time (s)")
    ax.set_ylabel("kinetic energy, trans + rot (J)")
    ax.set_title("%s, N = %d" % (scene, n))
    ax.legend(fontsize=8)
    fig.tight_layout()
    files.append(os.path.join(out, "%s.%d.ke.png" % (scene, n)))
    fig.savefig(files[-1], dpi=90)
    plt.close(fig)
    if scene == "silo":
        fig, (a1, a2) = plt.subplots(1, 2, figsize=(9, 3.6))
        for m in METHODS:
            r = R[m]
            a1.plot(r["t"], r["m"], color=COLORS[m], label=LABELS[m])
            tc, w = windowed_rate(r["t"], r["m"])
            a2.plot(tc, w, color=COLORS[m], drawstyle="steps-mid", label=LABELS[m])
            if math.isfinite(r["rate"]):
                a2.hlines(r["rate"], r["fit0"], r["fit1"], colors=COLORS[m], linestyles="--")
        a1.set_xlabel("time (s)")
        a1.set_ylabel("mass in the silo (kg)")
        a2.set_xlabel("time (s)")
        a2.set_ylabel("discharge rate W (kg/s), 0.5 s windows")
        a1.legend(fontsize=8)
        a2.set_title("dashed: steady rate (fit)", fontsize=9)
        fig.tight_layout()
        files.append(os.path.join(out, "%s.%d.discharge.png" % (scene, n)))
        fig.savefig(files[-1], dpi=90)
        plt.close(fig)
    else:
        fig, ax = plt.subplots(figsize=(6, 3.6))
        for m in METHODS:
            r = R[m]
            first = True
            for rb, hb, flank, p in r["fits"]:
                ax.plot(rb, hb, ".", color=COLORS[m], ms=4,
                        label=LABELS[m] + " (4 quadrants)" if first else None)
                xs = rb[flank]
                ax.plot(xs, np.polyval(p, xs), "-", color=COLORS[m], lw=1)
                first = False
        ax.set_xlabel("distance from the pile axis (m)")
        ax.set_ylabel("surface height, highest sphere top (m)")
        ax.set_title("pile profile and flank fits (angle %.1f vs %.1f deg)"
                     % (R["native"]["angle"], R["fibre"]["angle"]), fontsize=9)
        ax.legend(fontsize=8)
        fig.tight_layout()
        files.append(os.path.join(out, "%s.%d.profile.png" % (scene, n)))
        fig.savefig(files[-1], dpi=90)
        plt.close(fig)
    return files


def cmd_report(a):
    R = {m: load_method(a, a.scene, m, a.N, a.tag) for m in METHODS}
    os.makedirs(a.out, exist_ok=True)
    text = table(a.scene, a.N, R)
    files = plots(a.scene, a.N, R, a.out)
    md = os.path.join(a.out, "%s.%d.md" % (a.scene, a.N))
    with open(md, "w") as f:
        f.write(text)
        f.write("\nPlots: " + ", ".join("`%s`" % os.path.basename(p) for p in files) + "\n")
    print(text)
    print("wrote " + md + " and " + ", ".join(files))


# ----------------------------------------------------------------------------- Beverloo

def beverloo_fit(D, W, d, rho_b):
    """Least squares of W = C rho_b sqrt(g) (D - k d)^2.5: W^(2/5) is linear in D."""
    y = np.power(W, 0.4)
    p = np.polyfit(D, y, 1)           # y = s D + c, s = (C rho_b sqrt g)^(2/5), c = -s k d
    s, c = p
    C = s ** 2.5 / (rho_b * math.sqrt(G))
    k = -c / (s * d)
    return C, k


def cmd_beverloo(a):
    res = {m: [] for m in METHODS}
    for D in a.D:
        tag = "D%g" % D
        for m in METHODS:
            logp = os.path.join(run_dir(a.workdir, "silo", a.N, tag), log_name("silo", m, a.N, tag))
            if not os.path.exists(logp):
                if not a.run:
                    die("missing %s (add --run)" % logp)
                run_one(a, "silo", m, a.N, tag, [("D", D)] + list(a.var or ()))
            r = load_method(a, "silo", m, a.N, tag)
            res[m].append((D, r["rate"], r["clogged"], r.get("mean_d", 0.75), r["m_open"]))
    # bulk density of the settled packing: solid fraction 0.6 (random packing) x density
    rho_b = 0.6 * RHO
    lines = ["| D (m) | " + " | ".join("W %s (kg/s)" % m for m in METHODS) + " |",
             "|---|" + "---|" * len(METHODS)]
    for i, D in enumerate(a.D):
        cells = []
        for m in METHODS:
            _, W, clog, _, _ = res[m][i]
            cells.append("%.2f%s" % (W, " (clogged)" if clog else ""))
        lines.append("| %g | %s |" % (D, " | ".join(cells)))
    lines.append("")
    fits = {}
    for m in METHODS:
        pts = [(D, W) for D, W, clog, _, _ in res[m] if math.isfinite(W) and W > 0 and not clog]
        d = float(np.mean([x[3] for x in res[m]]))
        if len(pts) >= 2:
            C, k = beverloo_fit(np.array([p[0] for p in pts]), np.array([p[1] for p in pts]),
                                d, rho_b)
            fits[m] = (C, k, d)
            lines.append("%s: C = %.3f, k = %.2f (d = mean diameter %.3f m, rho_b = %.2f kg/m^3,"
                         " %d diameters)" % (m, C, k, d, rho_b, len(pts)))
        else:
            lines.append("%s: fewer than two flowing diameters, no fit" % m)
    text = "\n".join(lines) + "\n"
    os.makedirs(a.out, exist_ok=True)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.6))
    for m in METHODS:
        D = np.array([x[0] for x in res[m]])
        W = np.array([x[1] for x in res[m]])
        ax.plot(D, W, "o", color=COLORS[m], label=LABELS[m])
        if m in fits:
            C, k, d = fits[m]
            xs = np.linspace(max(k * d, min(D) - 0.5), max(D) + 0.5, 50)
            ax.plot(xs, C * rho_b * math.sqrt(G) * np.maximum(xs - k * d, 0) ** 2.5, "-",
                    color=COLORS[m], lw=1, label="fit C = %.2f, k = %.2f" % (C, k))
    ax.set_xlabel("orifice diameter D (m)")
    ax.set_ylabel("steady discharge rate W (kg/s)")
    ax.set_title("Beverloo, silo N = %d" % a.N)
    ax.legend(fontsize=8)
    fig.tight_layout()
    png = os.path.join(a.out, "beverloo.%d.png" % a.N)
    fig.savefig(png, dpi=90)
    plt.close(fig)
    md = os.path.join(a.out, "beverloo.%d.md" % a.N)
    with open(md, "w") as f:
        f.write(text + "\nPlot: `%s`\n" % os.path.basename(png))
    print(text)
    print("wrote " + md + " and " + png)


# ----------------------------------------------------------------------------- seeds

def paired_stats(fibre, native):
    """Both twins' figure over seeds, paired by seed: fibre and native map a seed to a value
    (NaN where a run has none, such as a clogged silo). Each twin's mean, range and standard
    deviation are over its own seeds with a value; the difference fibre - native is over the
    seeds where both have one, with the standard error of its mean (the spread of the
    per-seed differences over sqrt(n)), and relative to native's mean over those seeds.
    "means" is the difference of the two twins' own means (each over its seeds with a value,
    as issue #14 compares them: a clog drops one twin's seed only), with the standard error
    sqrt(sd_f^2 / n_f + sd_n^2 / n_n), and relative to native's own mean."""
    def summary(v):
        x = np.array([y for y in v.values() if math.isfinite(y)], dtype=float)
        if len(x) == 0:
            return {"n": 0, "mean": float("nan"), "min": float("nan"), "max": float("nan"),
                    "sd": float("nan")}
        return {"n": len(x), "mean": float(x.mean()), "min": float(x.min()),
                "max": float(x.max()), "sd": float(x.std(ddof=1)) if len(x) > 1 else float("nan")}
    both = [k for k in fibre if k in native and math.isfinite(fibre[k])
            and math.isfinite(native[k])]
    d = np.array([fibre[k] - native[k] for k in both], dtype=float)
    base = float(np.mean([native[k] for k in both])) if both else float("nan")
    out = {"fibre": summary(fibre), "native": summary(native), "paired": len(both)}
    out["diff"] = float(d.mean()) if len(d) else float("nan")
    out["diff_se"] = float(d.std(ddof=1) / math.sqrt(len(d))) if len(d) > 1 else float("nan")
    out["rel"] = out["diff"] / base if base else float("nan")
    out["rel_se"] = out["diff_se"] / abs(base) if base else float("nan")
    f, n = out["fibre"], out["native"]
    out["means"] = f["mean"] - n["mean"]
    out["means_se"] = (math.sqrt(f["sd"] ** 2 / f["n"] + n["sd"] ** 2 / n["n"])
                       if f["n"] > 1 and n["n"] > 1 else float("nan"))
    out["means_rel"] = out["means"] / n["mean"] if n["n"] and n["mean"] else float("nan")
    out["means_rel_se"] = (out["means_se"] / abs(n["mean"]) if n["n"] and n["mean"]
                           else float("nan"))
    return out


# (key in load_method's result, label, format, compared relative to native)
SEED_FIGURES = {"material": (("height", "height (m)", "%.2f", True),
                             ("angle", "angle (deg)", "%.1f", False)),
                "silo": (("rate", "discharge rate (kg/s)", "%.2f", True),)}
WALL_FIGURE = ("wall_per_s", "wall s / simulated s", "%.2f", True)


def run_prefix(a, method):
    """A twin's run directories' prefix: --native-tag's for native, else --tag's."""
    return (a.native_tag if method == "native" and a.native_tag else a.tag) or "seeds"


def seed_tag(a, seed, method="fibre", prefix=None):
    """The run directory's tag of a seed's twin: prefix's, else run_prefix's."""
    return "%s_s%s" % (prefix or run_prefix(a, method), seed)


def seed_figures(a, method, tag):
    """One seed's run, its end figures only; a clogged silo's rate is NaN."""
    r = load_method(a, a.scene, method, a.N, tag, history=False)
    if a.scene == "silo" and r["clogged"]:
        r["rate"] = float("nan")
    return r


def read_seeds_table(path, scene):
    """A seeds table's figures (cmd_seeds' form): {method: {key: {seed: value}}}, NaN where the
    table says clogged."""
    figures = SEED_FIGURES[scene] + (WALL_FIGURE,)
    values = {m: {key: {} for key, _, _, _ in figures} for m in METHODS}
    for line in open(path):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 1 + len(METHODS) * len(figures) or not cells[0].isdigit():
            continue
        for i, (m, (key, _, _, _)) in enumerate((m, f) for m in METHODS for f in figures):
            text = cells[1 + i]
            values[m][key][cells[0]] = float("nan") if text == "clogged" else float(text)
    if not values["native"][figures[0][0]]:
        die("%s: no seed rows of the %s scene" % (path, scene))
    return values


def run_missing_seeds(a, methods=METHODS):
    """Runs (with --run) each seed's twins that have no log yet, a.jobs at a time."""
    jobs = []
    for seed in a.seeds:
        for m in methods:
            tag = seed_tag(a, seed, m)
            own = a.fibre_var if m == "fibre" else a.native_var
            logp = os.path.join(run_dir(a.workdir, a.scene, a.N, tag),
                                log_name(a.scene, m, a.N, tag))
            if os.path.exists(logp):
                continue
            if not a.run:
                die("missing %s (add --run)" % logp)
            jobs.append((m, tag, [("seed", seed)] + list(a.var or ()) + list(own or ())))
    if jobs:
        from concurrent.futures import ThreadPoolExecutor
        with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
            for f in [pool.submit(run_one, a, a.scene, m, a.N, tag, v) for m, tag, v in jobs]:
                f.result()


def cmd_seeds(a):
    former = read_seeds_table(a.from_table, a.scene) if a.from_table else None
    if former:
        missing = [s for s in a.seeds if s not in former["native"][WALL_FIGURE[0]]]
        if missing:
            die("--from-table %s has no row for seeds %s" % (a.from_table, " ".join(missing)))
    run_missing_seeds(a, ("fibre",) if former else METHODS)
    figures = SEED_FIGURES[a.scene] + (WALL_FIGURE,)
    values = {m: {key: {} for key, _, _, _ in figures} for m in METHODS}  # seed -> value
    clogs = {m: [] for m in METHODS}
    rows = []
    for seed in a.seeds:
        cells = []
        for m in METHODS:
            if former and m == "native":
                r = {key: former[m][key][seed] for key, _, _, _ in figures}
                r["clogged"] = a.scene == "silo" and not math.isfinite(r["rate"])
            else:
                r = seed_figures(a, m, seed_tag(a, seed, m))
            if a.scene == "silo" and r["clogged"]:
                clogs[m].append(seed)
            for key, _, fmt, _ in figures:
                values[m][key][seed] = r[key]
                cells.append(fmt % r[key] if math.isfinite(r[key]) else "clogged")
        rows.append("| %s | %s |" % (seed, " | ".join(cells)))
    typed = ["%s: %s" % (who, " ".join("-var %s %s" % tuple(kv) for kv in vs))
             for who, vs in (("both", a.var), ("fix", a.fibre_var), ("native", a.native_var)) if vs]
    head = ["%s %s" % (m, label) for m in METHODS for _, label, _, _ in figures]
    lines = ["%s, N %d, %d seeds%s" % (a.scene, a.N, len(a.seeds),
                                      "; " + "; ".join(typed) if typed else ""),
             "", "| seed | " + " | ".join(head) + " |", "|---|" + "---|" * len(head)] + rows
    lines += ["", "| figure | native: mean (range), sd | fix: mean (range), sd | fix - native, "
              "paired by seed (standard error) | fix - native, the means (standard error) |",
              "|---|---|---|---|---|"]

    def difference(st, fmt, relative, means=False):
        """The paired difference (or, with means, the difference of the means) and its error."""
        rel, rel_se, value, se = (st[k] for k in (
            ("means_rel", "means_rel_se", "means", "means_se") if means
            else ("rel", "rel_se", "diff", "diff_se")))
        if relative:
            return "%+.1f%% (%.1f%%)" % (100 * rel, 100 * rel_se)
        return ("%+" + fmt[1:] + " (" + fmt + ")") % (value, se)

    def twin(t, fmt):
        return "%s (%s..%s), %s, %d seeds" % (fmt % t["mean"], fmt % t["min"], fmt % t["max"],
                                              fmt % t["sd"], t["n"])
    # with --from-table the twins' wall seconds are of different machines: not compared
    compared = [f for f in figures if not (former and f is WALL_FIGURE)]
    for key, label, fmt, relative in compared:
        st = paired_stats(values["fibre"][key], values["native"][key])
        lines.append("| %s | %s | %s | %s over %d seeds | %s |" % (
            label, twin(st["native"], fmt), twin(st["fibre"], fmt),
            difference(st, fmt, relative), st["paired"], difference(st, fmt, relative, True)))
    # a twin's runs of another setting, read as they are (no --run), or the former table's fix
    againsts = [(m, who, prefix, None) for m, who, prefix in (
        ("fibre", "fix", a.against_tag), ("native", "native", a.native_against_tag)) if prefix]
    if former:
        againsts.append(("fibre", "fix", os.path.basename(a.from_table), former["fibre"]))
    for m, who, prefix, table in againsts:
        other = {key: {} for key, _, _, _ in figures}
        for seed in a.seeds:
            r = ({key: table[key][seed] for key in other} if table
                 else seed_figures(a, m, seed_tag(a, seed, prefix=prefix)))
            for key, _, _, _ in figures:
                other[key][seed] = r[key]
        lines += ["", "| figure | %s (%s) - %s (%s), paired by seed (standard error) | the means "
                  "(standard error) |" % (who, run_prefix(a, m), who, prefix), "|---|---|---|"]
        for key, label, fmt, relative in compared:
            st = paired_stats(values[m][key], other[key])
            lines.append("| %s | %s over %d seeds | %s |" % (
                label, difference(st, fmt, relative), st["paired"],
                difference(st, fmt, relative, True)))
    if former:
        lines += ["", "Native's figures and wall seconds are those of `%s`, so no speed ratio."
                  % os.path.basename(a.from_table)]
    else:
        wall = {m: np.mean(list(values[m]["wall_per_s"].values())) for m in METHODS}
        lines += ["", "Speed: native / fix = %.2fx (mean wall seconds per simulated second)."
                  % (wall["native"] / wall["fibre"])]
    lines += ["%s clogged at seeds %s." % (m, " ".join(clogs[m])) for m in METHODS if clogs[m]]
    lines += ["", "Made with `compare.py %s`." % " ".join(
        "'%s'" % w if (" " in w or not w) else w for w in sys.argv[1:])]
    text = "\n".join(lines) + "\n"
    os.makedirs(a.out, exist_ok=True)
    md = os.path.join(a.out, "%s.%d.seeds.%s.md" % (a.scene, a.N, a.tag or "seeds"))
    with open(md, "w") as f:
        f.write(text)
    print(text)
    print("wrote " + md)


PICTURE_DECK = """units si
atom_style sphere
boundary f f f
read_data {data}
variable c atom z
dump img all image 1 picture.*.png v_c diameter view {view} zoom {zoom} size 480 360 box no 0.0
dump_modify img backcolor white amap min max ca 0.0 2 min blue max orange
run 0 pre no post no
"""


def cmd_picture(a):
    """PNG snapshot of a dump with LAMMPS's dump image (Debian's lmp has PNG support)."""
    d = run_dir(a.workdir, a.scene, a.N, a.tag)
    if a.scene == "material":
        dump = os.path.join(d, "pile.%s.%d.dump" % (a.method, a.N))
        view, zoom = "70 -30", 1.6
    else:
        dump = os.path.join(d, "silo.%s.%d.%s" % (a.method, a.N,
                                                  "filled.dump" if a.when == "filled" else "traj"))
        view, zoom = "85 -30", 1.3
    frames = read_frames(dump)
    if not frames:
        die("no frames in " + dump)
    k = -1 if a.when != "filled" else 0
    if a.when not in ("filled", "last"):
        k = min(range(len(frames)), key=lambda i: abs(frames[i][0] - int(a.when)))
    step, c = frames[k]
    lo = min(c["x"].min(), c["y"].min()) - 1
    hi = max(c["x"].max(), c["y"].max()) + 1
    os.makedirs(a.out, exist_ok=True)
    png = os.path.join(a.out, "%s.%d.%s.%s.png" % (a.scene, a.N, a.method, a.when))
    data = os.path.join(d, "picture.data")
    with open(data, "w") as f:
        f.write("snapshot of %s step %d\n\n%d atoms\n1 atom types\n" % (dump, step, len(c["x"])))
        f.write("%g %g xlo xhi\n%g %g ylo yhi\n%g %g zlo zhi\n\nAtoms # sphere\n\n"
                % (lo, hi, lo, hi, c["z"].min() - 1, c["z"].max() + 1))
        for k in range(len(c["x"])):
            f.write("%d 1 %.6g 1 %.6g %.6g %.6g\n" % (k + 1, 2 * c["radius"][k], c["x"][k],
                                                       c["y"][k], c["z"][k]))
    deck = PICTURE_DECK.format(data=data, view=view, zoom=zoom)
    deck_path = os.path.join(d, "in.picture")
    with open(deck_path, "w") as f:
        f.write(deck)
    for old in glob.glob(os.path.join(d, "picture.*.png")):
        os.remove(old)
    rc = subprocess.call([a.lmp, "-in", deck_path, "-log", "none", "-screen", "none"], cwd=d)
    made = glob.glob(os.path.join(d, "picture.*.png"))
    if rc == 0 and made:
        shutil.move(made[0], png)
    if rc != 0 or not os.path.exists(png):
        die("dump image failed for " + dump)
    print("wrote %s (%d bytes, step %d)" % (png, os.path.getsize(png), step))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="\n".join(__doc__.splitlines()[2:]))
    p.add_argument("--workdir", default=DEFAULT_WORK, help="run directories (%(default)s)")
    p.add_argument("--lmp", default="lmp", help="native LAMMPS (%(default)s)")
    p.add_argument("--lmp-fibre", default=os.path.join(REPO, "build", "fix", "lmp_fibre"),
                   help="LAMMPS with fix fibre_contact (%(default)s)")
    p.add_argument("--mpirun", default="mpirun")
    p.add_argument("--np", type=int, default=1, help="MPI processes per run")
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run", help="run the decks of a scene")
    r.add_argument("scene", choices=PILE_SCENES)
    r.add_argument("--N", type=int, required=True)
    r.add_argument("--method", choices=("fibre", "native", "both"), default="both")
    r.add_argument("--tag", default=None)
    r.add_argument("--var", nargs=2, action="append", metavar=("NAME", "VALUE"))
    q = sub.add_parser("report", help="table and plots of one scene and size")
    q.add_argument("scene", choices=PILE_SCENES)
    q.add_argument("--N", type=int, required=True)
    q.add_argument("--tag", default=None)
    q.add_argument("--out", default=DEFAULT_OUT)
    b = sub.add_parser("beverloo", help="discharge rate against orifice diameter")
    b.add_argument("--N", type=int, required=True)
    b.add_argument("--D", type=float, nargs="+", required=True)
    b.add_argument("--run", action="store_true", help="run what is missing")
    b.add_argument("--var", nargs=2, action="append", metavar=("NAME", "VALUE"))
    b.add_argument("--out", default=DEFAULT_OUT)
    s = sub.add_parser("seeds", help="both twins over seeds, paired by seed")
    s.add_argument("scene", choices=PILE_SCENES)
    s.add_argument("--N", type=int, required=True)
    s.add_argument("--seeds", nargs="+", required=True)
    s.add_argument("--run", action="store_true", help="run what is missing")
    s.add_argument("--jobs", type=int, default=1, help="runs at a time (%(default)s)")
    s.add_argument("--tag", default=None, help="run directories' prefix (default: seeds)")
    s.add_argument("--var", nargs=2, action="append", metavar=("NAME", "VALUE"))
    s.add_argument("--fibre-var", nargs=2, action="append", metavar=("NAME", "VALUE"))
    s.add_argument("--native-var", nargs=2, action="append", metavar=("NAME", "VALUE"))
    s.add_argument("--native-tag", default=None,
                   help="native twin's run directories' prefix (default: --tag's)")
    s.add_argument("--against-tag", default=None,
                   help="also pair the fix with the fix's runs of this prefix")
    s.add_argument("--native-against-tag", default=None,
                   help="also pair native with native's runs of this prefix")
    s.add_argument("--from-table", default=None,
                   help="native's figures (and the former fix's) from this seeds table; "
                        "runs the fix only")
    s.add_argument("--out", default=DEFAULT_OUT)
    i = sub.add_parser("picture", help="PNG snapshot of a run with dump image")
    i.add_argument("scene", choices=PILE_SCENES)
    i.add_argument("--N", type=int, required=True)
    i.add_argument("--method", choices=METHODS, default="fibre")
    i.add_argument("--when", default="last",
                   help="last, filled (silo before opening) or a time step of the traj dump")
    i.add_argument("--tag", default=None)
    i.add_argument("--out", default=os.path.join(HERE, "..", "pictures"))
    a = p.parse_args()
    a.lmp_fibre = os.path.abspath(a.lmp_fibre)
    if a.N <= 0:
        die("--N must be positive")
    if a.np < 1:
        die("--np must be >= 1")
    {"run": cmd_run, "report": cmd_report, "beverloo": cmd_beverloo,
     "picture": cmd_picture, "seeds": cmd_seeds}[a.cmd](a)


if __name__ == "__main__":
    main()
