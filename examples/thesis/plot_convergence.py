#!/usr/bin/python3
"""Figures like the thesis's (sections 5-6, Figures 16-24) from fibre_analyze's output.

Convergence (one figure per form and measure): r_r = ||r|| / ||A||_F and the velocity error
against the normalized iteration n/N (N: the form's system size), one line per
preconditioner (colour) and Krylov method (line style), with a dotted line at 100 iterations.

Spectra (one figure per form): histograms of the eigenvalues of A (precond none) and P^-1 A
with logarithmic bins; the small eigenvalues, below lambda_r (the gap that defines
kappa_e = lambda_1 / lambda_r), in red as in the thesis's Figures 16 and 21.

Typical use, on the LAMMPS-poured pile that test_fibre_analyze leaves in the build tree:

    build/tools/fibre_analyze build/tests/fibre_analyze/pile400.sys \\
        --csv pile400.csv --spectra pile400
    /usr/bin/python3 examples/thesis/plot_convergence.py pile400.csv --spectra pile400 \\
        --out figures --title "LAMMPS pile, 400 bodies"

Needs numpy and matplotlib (Debian python3-numpy, python3-matplotlib); draws with Agg.
"""
import argparse
import glob
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
import numpy as np  # noqa: E402

import analyze_output  # noqa: E402  (this folder: the readers shared with make_results.py)
from analyze_output import METHOD_STYLES, PRECOND_COLOURS, method_name  # noqa: E402

REPORT_ITERATION = 100  # the thesis's dotted line and its Table 1


def read_history(path):
    """Runs {(form, method, precond): columns} and sizes {form: N} from the history CSV
    (method `uzawa` of older files read as `cg`)."""
    runs, sizes = analyze_output.read_history(path)
    return ({k: {c: np.asarray(v) for c, v in cols.items()} for k, cols in runs.items()},
            sizes)


def positive(values):
    """The values with non-positive entries masked out (log axes)."""
    return np.where(values > 0, values, np.nan)


def plot_convergence(runs, sizes, form, measure, ylabel, title, path, methods, preconds):
    keys = [k for k in runs if k[0] == form and k[1] in methods and k[2] in preconds]
    if not keys:
        return None
    n_size = sizes.get(form) or max(runs[k]["iteration"][-1] for k in keys)
    final = int(max(runs[k]["iteration"][-1] for k in keys))
    fig, ax = plt.subplots(figsize=(9, 5.5))
    for precond in preconds:
        for method in methods:
            run = runs.get((form, method, precond))
            if run is None:
                continue
            ax.semilogy(run["iteration"] / n_size, positive(run[measure]),
                        color=PRECOND_COLOURS.get(precond, "grey"),
                        linestyle=METHOD_STYLES.get(method, ":"), linewidth=1.1,
                        label=f"{method}, {precond}")
    ax.axvline(REPORT_ITERATION / n_size, color="grey", linestyle=":", linewidth=1.2,
               label=f"{REPORT_ITERATION} iterations")
    ax.set_xlabel("Normalized iterations [n/N]")
    ax.set_ylabel(ylabel)
    ax.set_title(f"{title}{form} form. A = ({n_size} x {n_size}). Final iteration: {final}")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7, ncol=3, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def read_spectrum(path):
    """Eigenvalues and header facts of one spectrum file written by fibre_analyze --spectra."""
    info = analyze_output.read_spectrum(path)
    if "form" not in info or "lambda_r" not in info:
        raise ValueError(f"{path}: not a fibre_analyze spectrum file")
    info["eigenvalues"] = np.asarray(info["eigenvalues"])
    return info


def plot_spectra(spectra, form, title, path, preconds):
    panels = [s for p in preconds for s in spectra if s["form"] == form and s["precond"] == p]
    if not panels:
        return None
    cols = min(len(panels), 3)
    rows = math.ceil(len(panels) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(5 * cols, 3.8 * rows), squeeze=False)
    for ax in axes.flat[len(panels):]:
        ax.axis("off")
    for ax, s in zip(axes.flat, panels):
        ev = s["eigenvalues"]
        ev = ev[ev > 0]
        lo, hi = np.log10(ev.min()), np.log10(ev.max())
        bins = np.logspace(lo, hi if hi > lo else lo + 1, 60)
        small = ev[ev < s["lambda_r"]]
        large = ev[ev >= s["lambda_r"]]
        ax.hist([large, small], bins=bins, stacked=True, color=["tab:blue", "tab:red"],
                label=[f"above the gap ({large.size})", f"small ({small.size})"])
        ax.set_xscale("log")
        ax.set_yscale("log")
        operator = "A" if s["precond"] == "none" else "P^-1 A"
        complete = "Ritz values" not in s.get("method", "")
        ax.set_title(f"{s['precond']}: {operator}. Effective cond: {s['kappa_e']:.4g}"
                     + ("" if complete else "\n(Lanczos Ritz values only)"), fontsize=9)
        ax.set_xlabel("eigenvalue")
        ax.set_ylabel("count")
        ax.legend(fontsize=7)
    fig.suptitle(f"{title}Eigenvalues, {form} form")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def split_list(text, allowed, name=str):
    items = [name(t) for t in text.split(",") if t]
    bad = [t for t in items if t not in allowed]
    if bad or not items:
        raise argparse.ArgumentTypeError(
            f"unknown entries {bad} (allowed: {', '.join(allowed)})")
    return items


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("history", help="history CSV of fibre_analyze --csv")
    ap.add_argument("--spectra", metavar="PREFIX",
                    help="the prefix given to fibre_analyze --spectra: histograms too")
    ap.add_argument("--out", default=".", help="directory for the PNG files (default .)")
    ap.add_argument("--name", help="file name stem (default: the CSV's)")
    ap.add_argument("--title", default="", help="text that starts every title")
    ap.add_argument("--methods", default="cg,cr,minres",
                    type=lambda t: split_list(t, list(METHOD_STYLES), method_name),
                    help="Krylov methods to draw (default cg,cr,minres; uzawa: cg)")
    ap.add_argument("--precond", default="none,jacobi,block,fibre,tree",
                    type=lambda t: split_list(t, list(PRECOND_COLOURS)))
    ap.add_argument("--absolute-ve", action="store_true",
                    help="plot v_e itself (thesis) instead of v_e / ||dv*||")
    args = ap.parse_args(argv)

    try:
        runs, sizes = read_history(args.history)
    except (OSError, ValueError) as e:
        print(f"plot_convergence: {e}", file=sys.stderr)
        return 2
    os.makedirs(args.out, exist_ok=True)
    stem = args.name or os.path.splitext(os.path.basename(args.history))[0]
    title = f"{args.title}. " if args.title else ""
    written = []
    forms = sorted({k[0] for k in runs}, key=lambda f: (f != "contact", f))
    ve_column, ve_label = (("ve", "velocity error v_e = ||dv - dv*||") if args.absolute_ve else
                           ("ve_rel", "relative velocity error ||dv - dv*|| / ||dv*||"))
    for form in forms:
        for measure, label, suffix in (("rr", "relative residual r_r = ||r|| / ||A||_F", "rr"),
                                       (ve_column, ve_label, "ve")):
            written.append(plot_convergence(
                runs, sizes, form, measure, label, title,
                os.path.join(args.out, f"{stem}_{form}_{suffix}.png"), args.methods,
                args.precond))
    if args.spectra:
        files = sorted(f for f in glob.glob(glob.escape(args.spectra) + "_*_*.csv")
                       if not f.endswith("_kappa.csv"))
        try:
            spectra = [read_spectrum(f) for f in files]
        except (OSError, ValueError) as e:
            print(f"plot_convergence: {e}", file=sys.stderr)
            return 2
        if not spectra:
            print(f"plot_convergence: no spectrum files {args.spectra}_<form>_<precond>.csv",
                  file=sys.stderr)
            return 2
        for form in sorted({s["form"] for s in spectra}, key=lambda f: (f != "contact", f)):
            written.append(plot_spectra(
                spectra, form, title, os.path.join(args.out, f"{stem}_{form}_spectra.png"),
                args.precond))
    for path in written:
        if path:
            print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
