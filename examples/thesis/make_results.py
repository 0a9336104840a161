#!/usr/bin/python3
"""The ONE command of the thesis reproduction (issue 6): runs fibre_analyze on the exported
systems, writes the small CSVs to examples/thesis/data/, the figures to examples/thesis/fig/
and examples/thesis/RESULTS.md.

    /usr/bin/python3 examples/thesis/make_results.py [--tool build/tools/fibre_analyze]
        [--jobs 2] [--reuse]

Inputs: examples/thesis/systems/{silo,material}{350,700,1400,2600,5000}.sys, written by
examples/thesis/export.sh (run it first where they are missing; this script never simulates).
Raw outputs (full histories, eigenvalues, stdout) go to examples/thesis/work/ (not committed);
--reuse skips every fibre_analyze run whose stdout there is complete (ends with 'total').

Experiments (caps chosen so that the whole thing runs in about an hour on 2 loaded cores;
the weights and combine experiments on N = 350 and 700, Sigma scaling on N = 700):
- main: both forms x cg (the thesis's Uzawa), cr, minres x none, jacobi, block, fibre, tree, z weight, up to
  N iterations (N = the form's size), capped (CONTACT_CAP / BODY_CAP below) where N is large;
  spectra dense up to 3000 unknowns, Lanczos (LANCZOS_STEPS_MAIN steps at most) above.
- weights: fibre and tree with the z, straight and impulse edge weights (cg, cr).
- sigma: Sigma x 1e-4 .. 1e2 on the 700 systems (none, block, fibre, tree; cg, cr).
- combine: multipreconditioning (fibre_analyze --combine) against tree alone.
Needs numpy and matplotlib (Debian python3-numpy, python3-matplotlib).
"""
import argparse
import concurrent.futures as cf
import csv
import math
import os
import re
import subprocess
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import analyze_output  # noqa: E402  (this folder: the readers shared with plot_convergence.py)
from analyze_output import METHOD_STYLES as STYLES, METHODS, method_name  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SYSDIR = os.path.join(HERE, "systems")
WORK = os.path.join(HERE, "work")
DATA = os.path.join(HERE, "data")
FIG = os.path.join(HERE, "fig")

SCENES = ["silo", "material"]
SIZES = [350, 700, 1400, 2600, 5000]
PRECONDS = ["none", "jacobi", "block", "fibre", "tree"]
COMBOS = ["add_fibre_tree", "mul_tree_fibre", "add_fibre_zs", "add_tree_zs"]
WEIGHTS = ["z", "straight", "impulse"]
SIGMA_SCALES = ["1e-4", "1e-2", "1", "1e2"]
SIDE_SIZES = [350, 700]                # weights and combine experiments
SIGMA_SIZES = [700]                    # sigma-scaling experiment
CONTACT_CAP = {True: 3000, False: 1000}  # full N when N <= 3000, else 1000 iterations
BODY_CAP = 400                         # body form: at most 400 iterations (converges by ~100)
BODY_CAP_LARGE = 400
SIDE_MAXITER = 400                     # weights, sigma, combine runs
DENSE_MAX = 3000                       # dense spectra up to this size, Lanczos above
LANCZOS_STEPS = 300                    # side experiments
LANCZOS_STEPS_MAIN = 1000              # main runs
REPORT = 100
TARGET = 1e-6

# The thesis's Table 1 (fibre preconditioner, contact form: r_r and v_e at 100 iterations)
# and Table 2 (kappa_e without / with the fibre preconditioner; None = "X").
THESIS_BODIES = {"silo": [346, 668, 1377, 2567, 4988], "material": [313, 631, 1271, 2514, 5035]}
THESIS_T1 = {  # (scene, index) -> {method: (r_r, v_e)}; the thesis's Uzawa is cg
    ("silo", 0): {"cg": (-10, -5), "cr": (-12, -5), "minres": (-11, -5)},
    ("silo", 1): {"cg": (-8, -3), "cr": (-10, -3), "minres": (-8, -3)},
    ("silo", 2): {"cg": (-8, -2), "cr": (-10, -3), "minres": (-8, -3)},
    ("silo", 3): {"cg": (-6, 0), "cr": (-8, 0), "minres": (-6, 0)},
    ("silo", 4): {"cg": (-7, -2), "cr": (-9, -2), "minres": (-8, -2)},
    ("material", 0): {"cg": (-10, -5), "cr": (-11, -5), "minres": (-10, -5)},
    ("material", 1): {"cg": (-8, -3), "cr": (-9, -3), "minres": (-8, -3)},
    ("material", 2): {"cg": (-8, -3), "cr": (-9, -3), "minres": (-8, -3)},
    ("material", 3): {"cg": (-6, -1), "cr": (-8, -1), "minres": (-7, -1)},
    ("material", 4): {"cg": (-6, -1), "cr": (-8, -1), "minres": (-7, -1)},
}
THESIS_T2 = {"silo": [(72906, 159), (123656, 466), (141024, 580), (228939, 5236), (None, None)],
             "material": [(630634, 302), (746710, 1000), (910868, 499), (790574, 994),
                          (None, None)]}

COLOURS = {**analyze_output.PRECOND_COLOURS, "add_fibre_tree": "tab:purple",
           "mul_tree_fibre": "tab:brown", "add_fibre_zs": "tab:olive", "add_tree_zs": "tab:pink"}


# ---------------------------------------------------------------- running fibre_analyze

def set_sysdir(path):
    global SYSDIR
    SYSDIR = os.path.abspath(path)


def system_path(name):
    return os.path.join(SYSDIR, name + ".sys")


def system_sizes(path):
    """(bodies, contacts, rows) read from the head of a system file."""
    bodies = contacts = rows = None
    with open(path) as f:
        for line in f:
            w = line.split()
            if not w:
                continue
            if w[0] == "rows":
                rows = int(w[1])
            elif w[0] == "bodies":
                bodies = int(w[1])
            elif w[0] == "contacts":
                contacts = int(w[1])
                break
    return bodies, contacts, rows


def complete(out):
    if not os.path.exists(out):
        return False
    with open(out) as f:
        text = f.read()
    return "\ntotal " in text


def run_tool(job, tool, reuse):
    name, args = job
    out = os.path.join(WORK, name + ".txt")
    if reuse and complete(out):
        return name, 0.0, "reused"
    t0 = time.time()
    with open(out, "w") as f:
        rc = subprocess.call(["nice", "-n", "5", tool] + args, stdout=f,
                             stderr=subprocess.STDOUT)
    return name, time.time() - t0, f"rc {rc}"


def kappa_args(n):
    if n <= DENSE_MAX:
        return ["--kappa", "dense"]
    return ["--kappa", "lanczos", "--lanczos-steps", str(LANCZOS_STEPS_MAIN)]


def jobs_for(name, info):
    bodies, contacts, rows = info
    nc, nb = contacts * rows, 6 * bodies
    sysf = system_path(name)
    w = lambda s: os.path.join(WORK, s)  # noqa: E731
    jobs = []
    mc = nc if nc <= CONTACT_CAP[True] else CONTACT_CAP[False]
    mb = min(nb, BODY_CAP)
    for form, m, n in (("contact", mc, nc), ("body", mb, nb)):
        tag = f"{name}_{form}"
        jobs.append((tag, [sysf, "--form", form, "--maxiter", str(m), "--csv", w(tag + ".csv"),
                           "--spectra", w(tag)] + kappa_args(n)))
    size = int(re.sub(r"\D", "", name))
    if size in SIDE_SIZES:
        for wt in WEIGHTS:
            tag = f"{name}_weight_{wt}"
            jobs.append((tag, [sysf, "--form", "both", "--methods", "cg,cr", "--precond",
                               "fibre,tree", "--weight", wt, "--maxiter", str(SIDE_MAXITER),
                               "--csv", w(tag + ".csv"), "--spectra", w(tag),
                               "--kappa", "lanczos", "--lanczos-steps", str(LANCZOS_STEPS)]))
        tag = f"{name}_combine"
        jobs.append((tag, [sysf, "--form", "both", "--methods", "cg,cr", "--precond", "tree",
                           "--combine", ",".join(COMBOS), "--maxiter", str(SIDE_MAXITER),
                           "--csv", w(tag + ".csv"), "--spectra", w(tag),
                           "--kappa", "lanczos", "--lanczos-steps", str(LANCZOS_STEPS)]))
    if size in SIGMA_SIZES:
        for s in SIGMA_SCALES:
            tag = f"{name}_sigma_{s}"
            jobs.append((tag, [sysf, "--form", "both", "--methods", "cg,cr", "--precond",
                               "none,block,fibre,tree", "--sigma-scale", s, "--maxiter",
                               str(SIDE_MAXITER), "--csv", w(tag + ".csv"), "--spectra", w(tag),
                               "--kappa", "lanczos", "--lanczos-steps", str(LANCZOS_STEPS)]))
    return jobs


# ---------------------------------------------------------------- reading the outputs

def read_history(path):
    """{(form, method, precond): (iteration, rr, ve, ve_rel) arrays} (`uzawa` read as `cg`)."""
    runs, _ = analyze_output.read_history(path, ("iteration", "rr", "ve", "ve_rel"))
    return {k: (np.asarray(c["iteration"], dtype=int), np.asarray(c["rr"]), np.asarray(c["ve"]),
                np.asarray(c["ve_rel"])) for k, c in runs.items()}


def read_seconds(path):
    """{(form, precond, method): (iterations, seconds)} from the stdout run lines."""
    out, form = {}, None
    with open(path) as f:
        for line in f:
            m = re.match(r"== (\w+) form runs", line)
            if m:
                form = m.group(1)
                continue
            w = line.split()
            if form and len(w) == 11 and method_name(w[1]) in METHODS:
                try:
                    out[(form, w[0], method_name(w[1]))] = (int(w[2]), float(w[10]))
                except ValueError:
                    pass
    return out


def read_header(path):
    info = {}
    with open(path) as f:
        for line in f:
            m = re.search(r"(\d+) bodies, (\d+) contacts \((\d+) on walls\)", line)
            if m:
                info["bodies"], info["contacts"], info["walls"] = map(int, m.groups())
            m = re.search(r"mean Sigma / that = ([\d.e+-]+)", line)
            if m:
                info["sigma_rel"] = float(m.group(1))
            m = re.search(r"\|\|dv\*\|\| = ([\d.e+-]+)", line)
            if m:
                info["dv_norm"] = float(m.group(1))
            m = re.search(r"precond (fibre|tree)\s+setup.*: (\d+) \w+ covering (\d+) of (\d+)",
                          line)
            if m:
                info[m.group(1) + "_cover"] = (int(m.group(2)), int(m.group(3)),
                                               int(m.group(4)))
    return info


def read_kappa(path):
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return {(r["form"], r["precond"]): r for r in csv.DictReader(f)}


def read_eigs(prefix, form, precond):
    path = f"{prefix}_{form}_{precond}.csv"
    if not os.path.exists(path):
        return None, None
    head = analyze_output.read_spectrum(path)
    return np.asarray(head.pop("eigenvalues")), head


def summary(hist):
    it, rr, ve, verel = hist
    k = np.where(it == REPORT)[0]
    i = k[0] if k.size else len(it) - 1
    hit = np.where(verel <= TARGET)[0]
    return {"rr100": rr[i], "ve100": ve[i], "verel100": verel[i],
            "at": int(it[i]), "to1e6": int(it[hit[0]]) if hit.size else None,
            "best": float(np.nanmin(verel)), "last": int(it[-1])}


def subsample(n):
    """Indices: every 5th iteration up to 100, then about 50 log-spaced ones."""
    idx = set(range(0, min(n, 101), 5))
    if n > 101:
        idx.update(np.unique(np.geomspace(100, n - 1, 50).astype(int)).tolist())
    idx.update({min(REPORT, n - 1), n - 1})
    return sorted(i for i in idx if i < n)


# ---------------------------------------------------------------- figures

def fig_convergence(name, form, hist, size, path, title):
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for (f, m, p), (it, rr, ve, verel) in sorted(hist.items()):
        if f != form:
            continue
        ix = subsample(len(it))
        x = it[ix] / size
        for ax, y in ((axes[0], rr[ix]), (axes[1], ve[ix])):
            ax.semilogy(x, np.where(y > 0, y, np.nan), color=COLOURS.get(p, "grey"),
                        linestyle=STYLES.get(m, "-"), linewidth=1.0, label=f"{m}, {p}")
    for ax, lab in ((axes[0], "r_r = ||r|| / ||A||_F"), (axes[1], "v_e = ||dv - dv*||")):
        ax.axvline(REPORT / size, color="grey", linestyle=":", linewidth=1.2)
        ax.set_xlabel(f"normalized iterations n/N (N = {size}; dotted: {REPORT} iterations)")
        ax.set_ylabel(lab)
        ax.grid(True, alpha=0.3)
    axes[1].legend(fontsize=6, ncol=3, loc="best")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def fig_spectra(prefix, form, path, title):
    panels = []
    for p in PRECONDS:
        ev, head = read_eigs(prefix, form, p)
        if ev is not None and ev.size:
            panels.append((p, ev, head))
    if not panels:
        return False
    fig, axes = plt.subplots(1, len(panels), figsize=(3.3 * len(panels), 3.0), squeeze=False)
    for ax, (p, ev, head) in zip(axes.flat, panels):
        ev = ev[ev > 0]
        lo, hi = np.log10(ev.min()), np.log10(ev.max())
        bins = np.logspace(lo, hi if hi > lo else lo + 1, 50)
        small, large = ev[ev < head["lambda_r"]], ev[ev >= head["lambda_r"]]
        ax.hist([large, small], bins=bins, stacked=True, color=["tab:blue", "tab:red"])
        ax.set_xscale("log")
        ax.set_yscale("log")
        ritz = "dense" not in head.get("method", "") and "body-space" not in head.get("method", "")
        ax.set_title(f"{p}: {'A' if p == 'none' else 'P^-1 A'}, kappa_e {head['kappa_e']:.3g}"
                     + ("\n(Lanczos Ritz values)" if ritz else ""), fontsize=8)
        ax.tick_params(labelsize=7)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)
    return True


# ---------------------------------------------------------------- main

def fmt(v):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.1e}"


def exp10(e):
    return f"1e{e}" if e != 0 else "1e0"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tool", default=os.path.join(ROOT, "build", "tools", "fibre_analyze"))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--reuse", action="store_true")
    ap.add_argument("--only", help="comma-separated system names (default: all 10)")
    ap.add_argument("--systems", default=SYSDIR, help="directory of the exported systems")
    args = ap.parse_args()
    set_sysdir(args.systems)
    for d in (WORK, DATA, FIG):
        os.makedirs(d, exist_ok=True)

    names = [f"{s}{n}" for s in SCENES for n in SIZES]
    if args.only:
        names = [n for n in names if n in args.only.split(",")]
    present = [n for n in names if os.path.exists(system_path(n))]
    missing = [n for n in names if n not in present]
    if missing:
        print("missing systems (run examples/thesis/export.sh):", " ".join(missing))
    infos = {n: system_sizes(system_path(n)) for n in present}
    jobs = [j for n in present for j in jobs_for(n, infos[n])]
    # largest first so that the pool stays busy
    jobs.sort(key=lambda j: -os.path.getsize(j[1][0]))
    t_all = time.time()
    timings = {}
    with cf.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for name, secs, status in pool.map(lambda j: run_tool(j, args.tool, args.reuse), jobs):
            timings[name] = secs
            print(f"{name}: {status}, {secs:.0f} s", flush=True)
    print(f"fibre_analyze runs: {time.time() - t_all:.0f} s")
    write_everything(present, missing, timings)
    return 0


def write_everything(present, missing, timings):
    rows, kap, heads = [], [], {}
    for name in present:
        scene = re.sub(r"\d", "", name)
        size = int(re.sub(r"\D", "", name))
        for form in ("contact", "body"):
            tag = f"{name}_{form}"
            txt = os.path.join(WORK, tag + ".txt")
            if not complete(txt):
                print(f"{tag}: no complete output, left out")
                continue
            head = read_header(txt)
            heads[name] = head
            hist = read_history(os.path.join(WORK, tag + ".csv"))
            secs = read_seconds(txt)
            nsize = {"contact": infos_size(head, "contact"), "body": 6 * head["bodies"]}[form]
            for (f, m, p), h in hist.items():
                s = summary(h)
                its, sec = secs.get((f, p, m), (None, None))
                rows.append({"scene": scene, "N": size, "bodies": head["bodies"],
                             "contacts": head["contacts"], "form": f, "method": m, "precond": p,
                             "size": nsize, "iterations": s["last"], **s,
                             "ms_per_iter": 1e3 * sec / its if its else None})
            # subsampled history CSV
            with open(os.path.join(DATA, f"hist_{tag}.csv"), "w") as out:
                out.write("method,precond,iteration,rr,ve,ve_rel\n")
                for (f, m, p), (it, rr, ve, verel) in sorted(hist.items()):
                    for i in subsample(len(it)):
                        out.write(f"{m},{p},{it[i]},{rr[i]:.4e},{ve[i]:.4e},{verel[i]:.4e}\n")
            fig_convergence(name, form, hist, nsize, os.path.join(FIG, f"conv_{tag}.png"),
                            f"{scene}, {head['bodies']} bodies, {form} form (N = {nsize})")
            fig_spectra(os.path.join(WORK, tag), form, os.path.join(FIG, f"spectra_{tag}.png"),
                        f"{scene}, {head['bodies']} bodies, {form} form: eigenvalues "
                        "(red: below the gap)")
            for (f, p), r in read_kappa(os.path.join(WORK, tag + "_kappa.csv")).items():
                kap.append({"scene": scene, "N": size, "bodies": head["bodies"], "form": f,
                            "precond": p, "n": r["n"], "kappa_e": float(r["kappa_e"]),
                            "lambda_1": float(r["lambda_1"]), "lambda_r": float(r["lambda_r"]),
                            "above_gap": r["above_gap"] if r["complete"] == "1" else "-",
                            "gap_ratio": float(r["gap_ratio"]), "method": r["method"],
                            "kappa": float(r["kappa"]),
                            "kappa_rank": kappa_rank(os.path.join(WORK, tag), f, p,
                                                     6 * head["bodies"])})
    cols = ["scene", "N", "bodies", "contacts", "form", "method", "precond", "size",
            "iterations", "rr100", "ve100", "verel100", "at", "to1e6", "best", "ms_per_iter"]
    write_csv(os.path.join(DATA, "table1.csv"), rows, cols)
    write_csv(os.path.join(DATA, "table2_kappa.csv"), kap,
              ["scene", "N", "bodies", "form", "precond", "n", "kappa_e", "lambda_1",
               "lambda_r", "above_gap", "gap_ratio", "method", "kappa", "kappa_rank"])
    side = side_experiments(present)
    overview_figures(rows, kap, side)
    write_results_md(present, missing, rows, kap, heads, side, timings)


def kappa_rank(prefix, form, precond, rank):
    """lambda_1 / lambda_m with m = min(n, 6 bodies) (contact form: rank(G) <= 6 bodies, the
    most eigenvalues that G M^-1 G^T can add to Sigma; body form: m = n, the plain kappa).
    Only from complete (dense) spectra; None otherwise."""
    ev, head = read_eigs(prefix, form, precond)
    if ev is None or "dense" not in head.get("method", "") or ev.size == 0:
        return None
    ev = np.sort(ev)[::-1]
    m = min(ev.size, rank) if form == "contact" else ev.size
    return float(ev[0] / ev[m - 1])


def infos_size(head, form):
    return head["contacts"] * 6 if form == "contact" else head["bodies"] * 6


def write_csv(path, rows, cols):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.4e}" if isinstance(v, float) else v) for k, v in r.items()})


def side_experiments(present):
    """weights, sigma, combine: rows {exp, name, variant, form, method, precond, ...}."""
    out = {"weights": [], "sigma": [], "combine": []}
    for name in present:
        for exp, variants in (("weights", [f"weight_{w}" for w in WEIGHTS]),
                              ("sigma", [f"sigma_{s}" for s in SIGMA_SCALES]),
                              ("combine", ["combine"])):
            for v in variants:
                tag = f"{name}_{v}"
                txt = os.path.join(WORK, tag + ".txt")
                if not complete(txt):
                    continue
                hist = read_history(os.path.join(WORK, tag + ".csv"))
                secs = read_seconds(txt)
                kappa = read_kappa(os.path.join(WORK, tag + "_kappa.csv"))
                head = read_header(txt)
                if v == "sigma_1e-4":  # the thesis's regime: where the stagnation shows
                    for form in ("contact", "body"):
                        fig_convergence(name, form, hist, infos_size(head, form),
                                        os.path.join(FIG, f"conv_{name}_sigma1e-4_{form}.png"),
                                        f"{name}, Sigma x 1e-4 (Sigma/diag ~ "
                                        f"{head.get('sigma_rel', 0):.1g}), {form} form")
                for (f, m, p), h in hist.items():
                    s = summary(h)
                    its, sec = secs.get((f, p, m), (None, None))
                    k = kappa.get((f, p))
                    out[exp].append({"name": name, "variant": v.split("_", 1)[-1], "form": f,
                                     "method": m, "precond": p, **s,
                                     "kappa_e": float(k["kappa_e"]) if k else None,
                                     "kappa_method": k["method"] if k else "",
                                     "sigma_rel": head.get("sigma_rel"),
                                     "ms_per_iter": 1e3 * sec / its if its else None,
                                     "cover": head.get(p + "_cover")})
    cols = ["name", "variant", "form", "method", "precond", "rr100", "verel100", "to1e6",
            "best", "kappa_e", "kappa_method", "sigma_rel", "ms_per_iter"]
    for exp, rows in out.items():
        write_csv(os.path.join(DATA, f"{exp}.csv"), rows, cols)
    return out


def overview_figures(rows, kap, side):
    # kappa_e against N, per form and preconditioner
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, form in zip(axes, ("contact", "body")):
        for p in PRECONDS:
            for scene, mk in (("silo", "o-"), ("material", "s--")):
                pts = sorted((r["bodies"], r["kappa_e"]) for r in kap
                             if r["form"] == form and r["precond"] == p and r["scene"] == scene)
                if pts:
                    ax.loglog(*zip(*pts), mk, color=COLOURS[p], label=f"{scene}, {p}",
                              markersize=4)
        if form == "contact":
            for scene, mk in (("silo", "o"), ("material", "s")):
                for i, (a, b) in enumerate(THESIS_T2[scene]):
                    for v, c in ((a, "black"), (b, "tab:green")):
                        if v:
                            ax.loglog(THESIS_BODIES[scene][i], v, mk, mfc="none", color=c,
                                      markersize=8)
        ax.set_title(f"kappa_e, {form} form" + (" (open: thesis, none/fibre)"
                                                 if form == "contact" else ""), fontsize=9)
        ax.set_xlabel("bodies")
        ax.grid(True, alpha=0.3)
    axes[1].legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(os.path.join(FIG, "kappa_vs_bodies.png"), dpi=80)
    plt.close(fig)
    # iterations to ve_rel 1e-6 and ve_rel at 100 against N
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, form, meth in ((axes[0], "contact", "cr"), (axes[1], "body", "cg")):
        for p in PRECONDS:
            for scene, mk in (("silo", "o-"), ("material", "s--")):
                pts = sorted((r["bodies"], r["verel100"]) for r in rows
                             if r["form"] == form and r["precond"] == p and r["scene"] == scene
                             and r["method"] == meth)
                if pts:
                    ax.loglog(*zip(*pts), mk, color=COLOURS[p], label=f"{scene}, {p}",
                              markersize=4)
        ax.set_title(f"v_e / ||dv*|| at 100 iterations, {form} form, {meth}", fontsize=9)
        ax.set_xlabel("bodies")
        ax.grid(True, alpha=0.3)
    axes[1].legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(os.path.join(FIG, "ve100_vs_bodies.png"), dpi=80)
    plt.close(fig)
    # sigma scaling
    srows = side["sigma"]
    if srows:
        fig, axes = plt.subplots(1, 2, figsize=(11, 4))
        for ax, form, meth in ((axes[0], "contact", "cr"), (axes[1], "body", "cg")):
            for p in ["none", "block", "fibre", "tree"]:
                for name, mk in (("silo700", "o-"), ("material700", "s--")):
                    pts = sorted((float(r["variant"]), r["verel100"]) for r in srows
                                 if r["name"] == name and r["form"] == form and
                                 r["precond"] == p and r["method"] == meth)
                    if pts:
                        ax.loglog(*zip(*pts), mk, color=COLOURS[p], label=f"{name}, {p}",
                                  markersize=4)
            ax.set_xlabel("Sigma scale S (Sigma -> S Sigma)")
            ax.set_title(f"v_e / ||dv*|| at 100 iterations, {form} form, {meth}", fontsize=9)
            ax.grid(True, alpha=0.3)
        axes[1].legend(fontsize=6, ncol=2)
        fig.tight_layout()
        fig.savefig(os.path.join(FIG, "sigma_scaling.png"), dpi=80)
        plt.close(fig)


def kcell(k):
    if not k:
        return "missing"
    extra = f" ({k['kappa_rank']:.3g})" if k.get("kappa_rank") and k["form"] == "contact" else ""
    return f"{k['kappa_e']:.3g} / {k['kappa']:.3g}{extra}"


def cell(r):
    return f"{fmt(r['rr100'])} / {fmt(r['ve100'])}"


def write_results_md(present, missing, rows, kap, heads, side, timings):
    L = []
    add = L.append
    tmpl = open(os.path.join(HERE, "RESULTS.template.md")).read()
    idx = {(r["scene"], r["N"], r["form"], r["method"], r["precond"]): r for r in rows}
    kidx = {(r["scene"], r["N"], r["form"], r["precond"]): r for r in kap}

    # scenes table
    add("| scene | N (deck) | bodies | contacts (walls) | contact-form N | body-form N | "
        "mean Sigma / mean diag(G M^-1 G^T) | fibre cover | tree cover |")
    add("|---|---|---|---|---|---|---|---|---|")
    for name in present:
        h = heads.get(name)
        if not h:
            continue
        scene, size = re.sub(r"\d", "", name), int(re.sub(r"\D", "", name))
        fc, tc = h.get("fibre_cover"), h.get("tree_cover")
        add(f"| {scene} | {size} | {h['bodies']} | {h['contacts']} ({h['walls']}) | "
            f"{6 * h['contacts']} | {6 * h['bodies']} | {h.get('sigma_rel', 0):.2g} | "
            + (f"{fc[0]} fibres, {100 * fc[1] / max(fc[2], 1):.0f}% |" if fc else "- |")
            + (f" {tc[0]} trees, {100 * tc[1] / max(tc[2], 1):.0f}% |" if tc else " - |"))
    scenes_table = "\n".join(L)

    # Table 1
    L = []
    add = L.append
    add("Cells: r_r / v_e at iteration 100 (r_r = ||r||_2 / ||A||_F, v_e = ||dv - dv*||_2, "
        "the thesis's absolute velocity error). Thesis: its fibre-preconditioned contact-form "
        "value (orders of magnitude).")
    add("")
    add("| scene | bodies (thesis) | form | method | none | jacobi | block | fibre | tree | "
        "thesis fibre |")
    add("|---|---|---|---|---|---|---|---|---|---|")
    for scene in SCENES:
        for i, size in enumerate(SIZES):
            for form in ("contact", "body"):
                for m in METHODS:
                    rs = [idx.get((scene, size, form, m, p)) for p in PRECONDS]
                    if not any(rs):
                        continue
                    b = next(r for r in rs if r)["bodies"]
                    th = THESIS_T1[(scene, i)][m]
                    thesis = f"{exp10(th[0])} / {exp10(th[1])}" if form == "contact" else ""
                    add(f"| {scene} | {b} ({THESIS_BODIES[scene][i]}) | {form} | {m} | "
                        + " | ".join(cell(r) if r else "missing" for r in rs)
                        + f" | {thesis} |")
    table1 = "\n".join(L)

    # iterations to 1e-6
    L = []
    add = L.append
    add("| scene | bodies | form | method | none | jacobi | block | fibre | tree |")
    add("|---|---|---|---|---|---|---|---|---|")
    for scene in SCENES:
        for size in SIZES:
            for form, ms in (("contact", ["cr"]), ("body", ["cg", "cr"])):
                for m in ms:
                    rs = [idx.get((scene, size, form, m, p)) for p in PRECONDS]
                    if not any(rs):
                        continue
                    b = next(r for r in rs if r)["bodies"]
                    add(f"| {scene} | {b} | {form} | {m} | " + " | ".join(
                        ("-" if r is None else
                         (str(r["to1e6"]) if r["to1e6"] else f">{r['last']} ({r['best']:.0e})"))
                        for r in rs) + " |")
    table_iters = "\n".join(L)

    # cost per iteration
    L = []
    add = L.append
    add("| scene | bodies | form | ms/iteration cg: none | jacobi | block | fibre | tree |")
    add("|---|---|---|---|---|---|---|---|")
    for scene in SCENES:
        for size in SIZES:
            for form in ("contact", "body"):
                rs = [idx.get((scene, size, form, "cg", p)) for p in PRECONDS]
                if not any(rs):
                    continue
                b = next(r for r in rs if r)["bodies"]
                add(f"| {scene} | {b} | {form} | " + " | ".join(
                    f"{r['ms_per_iter']:.2f}" if r and r["ms_per_iter"] else "-" for r in rs)
                    + " |")
    table_cost = "\n".join(L)

    # Table 2
    L = []
    add = L.append
    add("| scene | bodies (thesis) | form | none | jacobi | block | fibre | tree | "
        "thesis none | thesis fibre | how (none; preconditioned) |")
    add("|---|---|---|---|---|---|---|---|---|---|---|")
    for scene in SCENES:
        for i, size in enumerate(SIZES):
            for form in ("contact", "body"):
                ks = [kidx.get((scene, size, form, p)) for p in PRECONDS]
                if not any(ks):
                    continue
                b = next(k for k in ks if k)["bodies"]
                t = THESIS_T2[scene][i] if form == "contact" else ("", "")
                tn = "X" if t[0] is None else str(t[0])
                tf = "X" if t[1] is None else str(t[1])
                how = sorted({k["method"].split(" ")[0] for k in ks if k})
                add(f"| {scene} | {b} ({THESIS_BODIES[scene][i]}) | {form} | "
                    + " | ".join(kcell(k) for k in ks)
                    + f" | {tn} | {tf} | {', '.join(how)} |")
    table2 = "\n".join(L)

    # weights
    L = []
    add = L.append
    add("| system | form | method | precond | z: v_e/‖dv*‖@100, to 1e-6, kappa_e | straight | "
        "impulse |")
    add("|---|---|---|---|---|---|---|")
    wi = {(r["name"], r["variant"], r["form"], r["method"], r["precond"]): r
          for r in side["weights"]}
    for name in present:
        for form, m in (("contact", "cr"), ("body", "cg")):
            for p in ("fibre", "tree"):
                cells = []
                for w in WEIGHTS:
                    r = wi.get((name, w, form, m, p))
                    cells.append("-" if r is None else
                                 f"{r['verel100']:.1e}, {r['to1e6'] or '>' + str(r['last'])}, "
                                 f"{fmt(r['kappa_e'])}")
                if any(c != "-" for c in cells):
                    add(f"| {name} | {form} | {m} | {p} | " + " | ".join(cells) + " |")
    table_w = "\n".join(L)

    # sigma
    L = []
    add = L.append
    add("| system | form | method | precond | " + " | ".join(
        f"S = {s}: v_e/‖dv*‖@100, to 1e-6, kappa_e" for s in SIGMA_SCALES) + " |")
    add("|---|---|---|---|" + "---|" * len(SIGMA_SCALES))
    si = {(r["name"], r["variant"], r["form"], r["method"], r["precond"]): r
          for r in side["sigma"]}
    sig_rel = {}
    for r in side["sigma"]:
        sig_rel[(r["name"], r["variant"])] = r["sigma_rel"]
    for name in present:
        for form, m in (("contact", "cr"), ("body", "cg")):
            for p in ("none", "block", "fibre", "tree"):
                cells = []
                for s in SIGMA_SCALES:
                    r = si.get((name, s, form, m, p))
                    cells.append("-" if r is None else
                                 f"{r['verel100']:.1e}, {r['to1e6'] or '>' + str(r['last'])}, "
                                 f"{fmt(r['kappa_e'])}")
                if any(c != "-" for c in cells):
                    add(f"| {name} | {form} | {m} | {p} | " + " | ".join(cells) + " |")
    sig_line = "; ".join(f"{n} S={s}: {v:.2g}" for (n, s), v in sorted(sig_rel.items()) if v)
    table_s = "\n".join(L) + ("\n\nmean Sigma / mean diag(G M^-1 G^T): " + sig_line
                              if sig_line else "")

    # combine
    L = []
    add = L.append
    add("| system | form | method | precond | to 1e-6 | v_e/‖dv*‖@100 | kappa_e | "
        "ms/iteration | ms to 1e-6 |")
    add("|---|---|---|---|---|---|---|---|---|")
    for r in side["combine"]:
        if (r["form"], r["method"]) not in (("contact", "cr"), ("body", "cg")):
            continue
        ms = r["ms_per_iter"]
        tot = f"{ms * r['to1e6']:.1f}" if ms and r["to1e6"] else "-"
        add(f"| {r['name']} | {r['form']} | {r['method']} | {r['precond']} | "
            f"{r['to1e6'] or '>' + str(r['last'])} | {r['verel100']:.1e} | "
            f"{fmt(r['kappa_e'])} | {ms:.2f} | {tot} |" if ms else
            f"| {r['name']} | {r['form']} | {r['method']} | {r['precond']} | "
            f"{r['to1e6'] or '>' + str(r['last'])} | {r['verel100']:.1e} | "
            f"{fmt(r['kappa_e'])} | - | - |")
    table_c = "\n".join(L)

    figs = []
    for name in present:
        for form in ("contact", "body"):
            for kind in ("conv", "spectra"):
                f = f"fig/{kind}_{name}_{form}.png"
                if os.path.exists(os.path.join(HERE, f)):
                    figs.append(f"[{kind} {name} {form}]({f})")
    missing_txt = ("Missing systems: " + ", ".join(missing) + " (run export.sh)."
                   if missing else "All 10 systems present.")
    total = 0.0  # the tools' own "total X s" lines: also right when --reuse skipped runs
    for fname in os.listdir(WORK):
        if fname.endswith(".txt"):
            with open(os.path.join(WORK, fname)) as f:
                m = re.search(r"\ntotal ([\d.]+) s", f.read())
            total += float(m.group(1)) if m else 0.0
    text = (tmpl.replace("@SCENES@", scenes_table).replace("@TABLE1@", table1)
            .replace("@ITERS@", table_iters).replace("@COST@", table_cost)
            .replace("@TABLE2@", table2).replace("@WEIGHTS@", table_w)
            .replace("@SIGMA@", table_s).replace("@COMBINE@", table_c)
            .replace("@FIGS@", " · ".join(figs)).replace("@MISSING@", missing_txt)
            .replace("@RUNTIME@", f"{total / 60:.0f} min of fibre_analyze runs (sum over "
                     "runs, measured by the tool)"))
    with open(os.path.join(HERE, "RESULTS.md"), "w") as f:
        f.write(text)
    print("wrote", os.path.join(HERE, "RESULTS.md"))


if __name__ == "__main__":
    sys.exit(main())
