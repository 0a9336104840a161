#!/usr/bin/python3
"""Moving-wall scenes: fix fibre_contact against its native twin (examples/drum, examples/shear).

  moving.py drum-run --omega W1 W2 ... [--method fibre|native|both] [--revs R] [--var N V]
      runs in.drum (lmp_fibre) and in.drum.native (Debian's lmp) in WORKDIR/drum.OMEGA.
  moving.py drum-report --omega W1 W2 ... [--out DIR]
      measures both twins at each speed and writes DIR/drum.md (a markdown table) and
      DIR/drum.profiles.png; prints the table.
  moving.py shear-run --U U1 U2 ... [--method ...] [--var N V]
      runs in.shear and in.shear.native in WORKDIR/shear.U.
  moving.py shear-report --U U1 U2 ... [--out DIR]
      the shear cell's effective friction and normal stress: DIR/shear.md.
  moving.py mixer-run --period T1 T2 ... [--method ...] [--revs R] [--var N V]
      runs in.mixer and in.mixer.native in WORKDIR/mixer.T.
  moving.py mixer-report --period T1 T2 ... [--out DIR]
      the blade's power and the bed's motion: DIR/mixer.md.
  moving.py pictures --omega W --U U --period T [--out DIR]
      the last snapshot of each twin of the three scenes, coloured by speed (LAMMPS dump
      image): DIR/{drum,shear,mixer}.METHOD.png.

Global options (--workdir, --np, --lmp, --lmp-fibre, --tag) go before the subcommand.

Drum, on the trajectory snapshots of the last revolution (20 per revolution), the same code for
both methods:

  angle     the dynamic angle of repose: the free surface is the highest sphere top (z + r)
            in bins of width 1 (the largest diameter) along x; a straight line is fitted to
            the bins within half a drum radius of the axis; the angle is atan|slope|, the
            mean over the snapshots with their standard deviation as the spread.
  layer     the flowing layer's depth: spheres within 1.5 of the line through the surface's
            centre (its point above the axis) normal to it; their velocity along the surface,
            downhill positive, averaged over the snapshots in depth bins of 0.5; the depth
            where that mean crosses zero (below it the bed turns with the drum, uphill).
  contained the largest distance of a sphere's surface from the axis (thermo c_rmax) over the
            whole run, against the drum radius: a sphere through the wall would exceed it by
            its diameter.
  speed     wall-clock seconds (thermo cpu) per simulated second.

Shear cell, from the thermo lines of the shear run after the first tskip seconds (a shear
strain of about 1):

  mu        the effective friction -sigma_xz / sigma_zz of the bulk (the grains more than 1.5
            from either wall: their per-atom virial stress summed), mean over the thermo lines
            and its standard error over 1 s blocks.
  p         the bulk's normal stress -sigma_zz (Pa).
  I         the inertial number gamma_dot d / sqrt(p / rho), gamma_dot = U / (Hc - 1).
  speed     wall-clock seconds per simulated second of the shear run.

Mixer, over the blade's last revolution:

  power     the power the blade puts into the grains: native, minus the pair forces on the
            blade atoms times their velocity (thermo c_power, averaged); fix fibre_contact,
            the growth of its wall work f_fc[17] over the revolution.
  ke        the grains' kinetic energy (translational + rotational), mean.
  lift      the rise of the grains' centre of mass over its height at rest.
  overlap   the deepest sphere-sphere overlap (grains and blade) over the revolution's
            snapshots (8 per revolution), in units of the smallest grain diameter (0.5).
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
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(REPO, "tools"))
import compare  # noqa: E402  (parse_thermo, read_frames)
import lammps_runs  # noqa: E402

METHODS = ("native", "fibre")
R_DRUM = 8.0  # scene.drum's default radius


def scene_dir(work, scene, value, tag=None):
    """WORKDIR/SCENE.VALUE[.TAG]: the run directory of one speed (or period) of a scene."""
    return os.path.join(work, "%s.%g%s" % (scene, value, "." + tag if tag else ""))


def scene_log(scene, method, value):
    return "log.%s.%s.%g" % (scene, method, value)


def speed_ratio(R, method):
    """The table's last column: native over fibre wall time, on the fibre row only."""
    if method != "fibre":
        return ""
    return "**%.2f**" % (R["native"]["wall_per_s"] / R["fibre"]["wall_per_s"])


def write_table(a, name, rows):
    """Prints a markdown table and writes it to OUT/NAME.md."""
    table = "\n".join(rows)
    print(table)
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, name + ".md"), "w") as f:
        f.write(table + "\n")


def run_twins(a, scene, d, log_of, variables):
    """Runs the scene's decks (in.SCENE with lmp_fibre, in.SCENE.native with lmp) in d."""
    os.makedirs(d, exist_ok=True)
    lammps_runs.copy_scene(REPO, scene, d)
    for m in (METHODS if a.method == "both" else (a.method,)):
        deck = "in.%s%s" % (scene, ".native" if m == "native" else "")
        exe = a.lmp if m == "native" else a.lmp_fibre
        cmd = lammps_runs.mpi_prefix(a.mpirun, a.np)
        cmd += ["nice", "-n", "5", exe, "-in", deck, "-log", log_of(m), "-screen", "none"]
        for k, v in list(variables) + list(a.var or ()):
            cmd += ["-var", k, str(v)]
        print("[%s] %s" % (d, " ".join(cmd)), flush=True)
        t0 = time.time()
        rc = subprocess.call(cmd, cwd=d, env=lammps_runs.lmp_env())
        print("   -> rc %d, %.1f s" % (rc, time.time() - t0), flush=True)
        if rc != 0:
            compare.die("%s failed (rc %d)" % (" ".join(cmd), rc))


def cmd_drum_run(a):
    for omega in a.omega:
        run_twins(a, "drum", scene_dir(a.workdir, "drum", omega, a.tag),
                  lambda m: scene_log("drum", m, omega),
                  [("omega", omega), ("revs", a.revs)])


def surface(c, radius=R_DRUM):
    """Fitted free surface of one snapshot: (intercept at x = 0, slope, bins x, bins top)."""
    x, top = c["x"], c["z"] + c["radius"]
    width = 2 * np.max(c["radius"])
    xb, hb = [], []
    for k in range(int(-radius / width), int(radius / width) + 1):
        s = (x >= k * width) & (x < (k + 1) * width)
        if s.any():
            xb.append((k + 0.5) * width)
            hb.append(np.max(top[s]))
    xb, hb = np.array(xb), np.array(hb)
    mid = np.abs(xb) <= 0.5 * radius
    slope, z0 = np.polyfit(xb[mid], hb[mid], 1)
    return z0, slope, xb, hb


def layer_profile(frames, fits, strip=1.5, dz=0.5):
    """Mean downhill velocity against depth below the surface, on the normal through x = 0."""
    depth_all, u_all = [], []
    for (_, c), (z0, slope) in zip(frames, fits):
        down = np.array([1.0, slope]) if slope < 0 else np.array([-1.0, -slope])
        down /= np.linalg.norm(down)
        up = np.array([-down[1], down[0]]) if down[0] > 0 else np.array([down[1], -down[0]])
        rel = np.stack([c["x"], c["z"] - z0], axis=1)
        along, depth = rel @ down, -(rel @ up)
        sel = (np.abs(along) < strip) & (depth > -1.0)
        depth_all.append(depth[sel])
        u_all.append(np.stack([c["vx"], c["vz"]], axis=1)[sel] @ down)
    depth, u = np.concatenate(depth_all), np.concatenate(u_all)
    edges = np.arange(0.0, depth.max() + dz, dz)
    centres, means = [], []
    for lo in edges[:-1]:
        s = (depth >= lo) & (depth < lo + dz)
        if s.sum() >= 3:
            centres.append(lo + dz / 2)
            means.append(float(np.mean(u[s])))
    centres, means = np.array(centres), np.array(means)
    thickness = float("nan")
    for k in range(1, len(means)):
        if means[k - 1] > 0 >= means[k]:
            f = means[k - 1] / (means[k - 1] - means[k])
            thickness = float(centres[k - 1] + f * (centres[k] - centres[k - 1]))
            break
    return centres, means, thickness


def measure(a, omega, method):
    d = scene_dir(a.workdir, "drum", omega, a.tag)
    blocks = compare.parse_thermo(os.path.join(d, scene_log("drum", method, omega)))
    sim = compare.sim_seconds(blocks)
    res = {"wall_per_s": compare.wall_seconds(blocks) / sim, "atoms": int(blocks[-1]["Atoms"][-1])}
    res["rmax"] = float(max(b["c_rmax"].max() for b in blocks[-1:]))
    tend = float(blocks[-1]["Time"][-1])
    frames = compare.read_frames(os.path.join(d, "drum.%s.%g.traj" % (method, omega)))
    dt = tend / max(frames[-1][0], 1)
    last = [(s, c) for s, c in frames if s * dt >= tend - 2 * math.pi / omega - 1e-9]
    fits = [surface(c)[:2] for _, c in last]
    angles = [math.degrees(math.atan(abs(s))) for _, s in fits]
    res["angle"], res["angle_sd"] = float(np.mean(angles)), float(np.std(angles))
    res["depth"], res["u"], res["layer"] = layer_profile(last, fits)
    res["frames"] = len(last)
    res["surface"] = surface(last[-1][1])
    res["final"] = last[-1][1]
    return res


def cmd_drum_report(a):
    rows = ["| omega (rad/s) | Froude omega^2 R / g | method | dynamic angle (deg) | spread (deg) | "
            "flowing layer (m) | largest r + radius from the axis (m) | wall s per simulated s "
            "| native / fibre wall time |", "|---|---|---|---|---|---|---|---|---|"]
    results = {}
    for omega in a.omega:
        R = {m: measure(a, omega, m) for m in METHODS}
        results[omega] = R
        for m in METHODS:
            r = R[m]
            ratio = speed_ratio(R, m)
            rows.append("| %g | %.3f | %s | %.1f | %.1f | %.2f | %.3f | %.2f | %s |" % (
                omega, omega ** 2 * R_DRUM / compare.G, m, r["angle"], r["angle_sd"],
                r["layer"], r["rmax"], r["wall_per_s"], ratio))
    write_table(a, "drum", rows)
    plot(results, os.path.join(a.out, "drum.profiles.png"))


def plot(results, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    n = len(results)
    fig, ax = plt.subplots(2, n, figsize=(4.5 * n, 8), squeeze=False)
    colors = {"native": "tab:blue", "fibre": "tab:red"}
    for k, (omega, R) in enumerate(sorted(results.items())):
        for m in METHODS:
            r = R[m]
            c = r["final"]
            if m == "fibre":
                ax[0, k].scatter(c["x"], c["z"], s=4, c=colors[m], alpha=0.4, label=m)
            z0, slope, xb, hb = r["surface"]
            ax[0, k].plot(xb, hb, ".-", color=colors[m], lw=0.8)
            ax[0, k].plot([-4, 4], [z0 - 4 * slope, z0 + 4 * slope], "--", color=colors[m],
                          label="%s %.1f deg" % (m, r["angle"]))
            ax[1, k].plot(r["u"], r["depth"], "o-", color=colors[m],
                          label="%s: layer %.2f m" % (m, r["layer"]))
        t = np.linspace(0, 2 * np.pi, 200)
        ax[0, k].plot(R_DRUM * np.cos(t), R_DRUM * np.sin(t), "k-", lw=0.8)
        ax[0, k].set_aspect("equal")
        ax[0, k].set_title("omega %g rad/s (Fr %.3f)" % (omega, omega ** 2 * R_DRUM / compare.G))
        ax[0, k].legend(fontsize=7)
        ax[1, k].axvline(0, color="k", lw=0.5)
        ax[1, k].invert_yaxis()
        ax[1, k].set_xlabel("downhill velocity (m/s)")
        ax[1, k].set_ylabel("depth below the surface (m)")
        ax[1, k].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    print("wrote", path)


def cmd_shear_run(a):
    for U in a.U:
        run_twins(a, "shear", scene_dir(a.workdir, "shear", U, a.tag),
                  lambda m: scene_log("shear", m, U),
                  [("U", U), ("tshear", a.tshear)])


def measure_shear(a, U, method, Hc=5.0, mean_d=0.75):
    blocks = compare.parse_thermo(os.path.join(scene_dir(a.workdir, "shear", U, a.tag),
                                               scene_log("shear", method, U)))
    b = blocks[-1]  # the shear run
    t = b["Time"] - b["Time"][0]
    keep = t >= a.tskip
    mu, p = b["v_muw"][keep], b["v_pzz"][keep]
    blocks_1s = [mu[(t[keep] >= s) & (t[keep] < s + 1)] for s in range(int(a.tskip), int(t[-1]))]
    means = [float(np.mean(x)) for x in blocks_1s if len(x)]
    sem = float(np.std(means) / math.sqrt(len(means))) if len(means) > 1 else float("nan")
    gamma_dot = U / (Hc - 1.0)
    res = {"mu": float(np.mean(mu)), "mu_sem": sem, "p": float(np.mean(p)),
           "wall_per_s": float(b["CPU"][-1] / t[-1])}
    res["I"] = gamma_dot * mean_d / math.sqrt(res["p"] / compare.RHO)
    return res


def cmd_shear_report(a):
    rows = ["| U (m/s) | method | effective friction -s_xz / s_zz | normal stress (Pa) | "
            "inertial number I | wall s per simulated s | native / fibre wall time |",
            "|---|---|---|---|---|---|---|"]
    for U in a.U:
        R = {m: measure_shear(a, U, m) for m in METHODS}
        for m in METHODS:
            r = R[m]
            ratio = speed_ratio(R, m)
            rows.append("| %g | %s | %.3f +- %.3f | %.1f | %.3f | %.2f | %s |" % (
                U, m, r["mu"], r["mu_sem"], r["p"], r["I"], r["wall_per_s"], ratio))
        rows.append("| %g | fibre / native | %.3f | %.2f | | | |" % (
            U, R["fibre"]["mu"] / R["native"]["mu"], R["fibre"]["p"] / R["native"]["p"]))
    write_table(a, "shear", rows)


def cmd_mixer_run(a):
    for period in a.period:
        run_twins(a, "mixer", scene_dir(a.workdir, "mixer", period, a.tag),
                  lambda m: scene_log("mixer", m, period), [("period", period), ("revs", a.revs)])


def measure_mixer(a, period, method):
    d = scene_dir(a.workdir, "mixer", period, a.tag)
    blocks = compare.parse_thermo(os.path.join(d, scene_log("mixer", method, period)))
    rest, b = blocks[-2], blocks[-1]
    t = b["Time"]
    last = t >= t[-1] - period - 1e-9
    if method == "native":
        power = float(np.mean(b["c_power"][last]))
    else:
        i = int(np.argmax(last))
        power = float((b["f_fc[17]"][-1] - b["f_fc[17]"][i]) / (t[-1] - t[i]))
    ke = b["c_ke"][last] + b["c_rot"][last]
    frames = compare.read_frames(os.path.join(d, "mixer.%s.traj" % method))
    dt = (t[-1] - t[0]) / max(b["Step"][-1] - b["Step"][0], 1)
    late = [c for s, c in frames if s * dt >= t[-1] - period - 1e-9]
    deepest = max(compare.max_pair_overlap(np.stack([c["x"], c["y"], c["z"]], axis=1),
                                           c["radius"]) for c in late)
    return {"power": power, "ke": float(np.mean(ke)), "lift": float(np.mean(b["v_zg"][last]) -
                                                                 rest["v_zg"][-1]),
            "overlap": deepest / 0.5, "wall_per_s": float(b["CPU"][-1] / (t[-1] - t[0]))}


def cmd_mixer_report(a):
    rows = ["| period (s) | tip speed (m/s) | method | blade power (W) | grains' kinetic energy (J) "
            "| centre of mass lift (m) | deepest overlap / d_min | wall s per simulated s | "
            "native / fibre wall time |", "|---|---|---|---|---|---|---|---|---|"]
    for period in a.period:
        R = {m: measure_mixer(a, period, m) for m in METHODS}
        for m in METHODS:
            r = R[m]
            ratio = speed_ratio(R, m)
            rows.append("| %g | %.2f | %s | %.0f | %.1f | %.3f | %.3f | %.2f | %s |" % (
                period, 2 * math.pi * 4.0 / period, m, r["power"], r["ke"], r["lift"],
                r["overlap"], r["wall_per_s"], ratio))
        rows.append("| %g | | fibre / native | %.3f | %.3f | %.3f | | | |" % (
            period, R["fibre"]["power"] / R["native"]["power"], R["fibre"]["ke"] / R["native"]["ke"],
            R["fibre"]["lift"] / R["native"]["lift"]))
    write_table(a, "mixer", rows)


PICTURE_DECK = """units si
atom_style sphere
boundary f f f
read_data {data}
variable c atom sqrt(vx*vx+vy*vy+vz*vz)
dump img all image 1 picture.*.png v_c diameter view {view} zoom {zoom} size 480 360 box no 0.0
dump_modify img backcolor white amap 0.0 {vmax} ca 0.0 2 min blue max orange
run 0 pre no post no
"""


def picture(a, d, dump, png, view, zoom, vmax):
    """The last frame of a trajectory dump as a PNG, coloured by speed (0 .. vmax)."""
    step, c = compare.read_frames(os.path.join(d, dump))[-1]
    data = os.path.join(d, "picture.data")
    lo = [c[k].min() - 1 for k in "xyz"]
    hi = [c[k].max() + 1 for k in "xyz"]
    with open(data, "w") as f:
        f.write("snapshot of %s step %d\n\n%d atoms\n1 atom types\n" % (dump, step, len(c["x"])))
        for k, (l, h) in enumerate(zip(lo, hi)):
            f.write("%g %g %slo %shi\n" % (l, h, "xyz"[k], "xyz"[k]))
        f.write("\nAtoms # sphere\n\n")
        for i in range(len(c["x"])):
            f.write("%d 1 %.6g 1 %.6g %.6g %.6g\n" % (i + 1, 2 * c["radius"][i], c["x"][i],
                                                       c["y"][i], c["z"][i]))
        f.write("\nVelocities\n\n")
        for i in range(len(c["x"])):
            f.write("%d %.6g %.6g %.6g 0 0 0\n" % (i + 1, c["vx"][i], c["vy"][i], c["vz"][i]))
    deck = os.path.join(d, "in.picture")
    with open(deck, "w") as f:
        f.write(PICTURE_DECK.format(data=data, view=view, zoom=zoom, vmax=vmax))
    for old in glob.glob(os.path.join(d, "picture.*.png")):
        os.remove(old)
    rc = subprocess.call([a.lmp, "-in", deck, "-log", "none", "-screen", "none"], cwd=d)
    made = glob.glob(os.path.join(d, "picture.*.png"))
    if rc != 0 or not made:
        compare.die("dump image failed for " + dump)
    shutil.move(made[0], png)
    print("wrote", png)


def cmd_pictures(a):
    os.makedirs(a.out, exist_ok=True)
    for m in METHODS:
        picture(a, scene_dir(a.drum_workdir, "drum", a.omega), "drum.%s.%g.traj" % (m, a.omega),
                os.path.join(a.out, "drum.%s.png" % m), "90 -90", 1.4, a.omega * R_DRUM)
        picture(a, scene_dir(a.workdir, "shear", a.U), "shear.%s.traj" % m,
                os.path.join(a.out, "shear.%s.png" % m), "80 -90", 1.3, a.U)
        picture(a, scene_dir(a.workdir, "mixer", a.period), "mixer.%s.traj" % m,
                os.path.join(a.out, "mixer.%s.png" % m), "60 -60", 1.4,
                2 * math.pi * 4.0 / a.period)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="\n".join(__doc__.splitlines()[2:]))
    p.add_argument("--workdir", default="/tmp/scenes/moving")
    p.add_argument("--lmp", default="lmp")
    p.add_argument("--lmp-fibre", default=os.path.join(REPO, "build", "fix", "lmp_fibre"))
    p.add_argument("--mpirun", default="mpirun")
    p.add_argument("--np", type=int, default=1)
    p.add_argument("--tag", default=None)
    sub = p.add_subparsers(dest="cmd", required=True)
    out = os.path.join(HERE, "results")
    # per scene: its swept variable, and the run's own option (name, default)
    for scene, swept, run_opt in (("drum", "--omega", ("--revs", 2.0)),
                                  ("shear", "--U", ("--tshear", 10.0)),
                                  ("mixer", "--period", ("--revs", 3.0))):
        r = sub.add_parser(scene + "-run")
        r.add_argument(swept, type=float, nargs="+", required=True)
        r.add_argument("--method", choices=("fibre", "native", "both"), default="both")
        r.add_argument(run_opt[0], type=float, default=run_opt[1])
        r.add_argument("--var", nargs=2, action="append", metavar=("NAME", "VALUE"))
        q = sub.add_parser(scene + "-report")
        q.add_argument(swept, type=float, nargs="+", required=True)
        q.add_argument("--out", default=out)
        if scene == "shear":
            q.add_argument("--tskip", type=float, default=3.0, help="seconds of shear left out")
    q = sub.add_parser("pictures")
    q.add_argument("--omega", type=float, default=0.3)
    q.add_argument("--U", type=float, default=2.0)
    q.add_argument("--period", type=float, default=4.0)
    q.add_argument("--drum-workdir", default="/tmp/scenes/drum")
    q.add_argument("--out", default=os.path.join(REPO, "examples", "pictures"))
    a = p.parse_args()
    a.lmp_fibre = os.path.abspath(a.lmp_fibre)
    {"drum-run": cmd_drum_run, "drum-report": cmd_drum_report, "shear-run": cmd_shear_run,
     "shear-report": cmd_shear_report, "mixer-run": cmd_mixer_run,
     "mixer-report": cmd_mixer_report, "pictures": cmd_pictures}[a.cmd](a)


if __name__ == "__main__":
    main()
