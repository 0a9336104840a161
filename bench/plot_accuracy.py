#!/usr/bin/env python3
"""Accuracy-cost curves of the nonsmooth step from fibre_accuracy's CSVs (accuracy_study.sh).

One panel per state: the velocity-change error (the larger of the translational and the
rotational relative errors) against the cost in K-product equivalents, one curve per family
(pgs, nncg, fbgs, apgd, cg, cg+nncg, and each solver stopped at its accuracy, pgs-tol ...),
the defaults marked. Prints, per state and family, the
cheapest setting that reaches 1e-3 in velocity and 1e-2 in impulses, as bench/README.md shows.
"""

import argparse
import csv
import math
import os

FAMILIES = ["pgs", "nncg", "fbgs", "apgd", "cg", "cg+nncg", "pgs-tol", "cg-tol", "nncg-tol",
            "fbgs-tol", "apgd-tol"]
DEFAULT = "(defaults)"  # fibre_accuracy's name of the empty setting


def family(setting):
    if "tol none" not in setting and setting != DEFAULT:
        for solver in ("pgs", "nncg", "fbgs", "apgd"):
            if "solver " + solver in setting:
                return solver + "-tol"
        return "cg-tol"
    if "solver pgs" in setting:
        return "pgs"
    if "solver nncg" in setting:
        return "nncg"
    if "solver fbgs" in setting:
        return "fbgs"
    if "solver apgd" in setting:
        return "apgd"
    if "sweep_cg yes" in setting:
        return "cg+nncg"
    return "cg"


def read(path):
    rows = []
    with open(path) as f:
        for r in csv.DictReader(f):
            for k in r:
                if k != "setting":
                    r[k] = float(r[k])
            r["velocity"] = max(r["dv_trans"], r["dv_rot"])
            r["impulse"] = max(r["lambda_n"], r["lambda_t"], r["lambda_roll"], r["lambda_twist"])
            r["family"] = family(r["setting"])
            rows.append(r)
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--png", default="accuracy_curves.png")
    p.add_argument("csv", nargs="+")
    args = p.parse_args()
    states = [(os.path.basename(c)[:-4], read(c)) for c in args.csv]
    print("| state | family | cheapest to velocity 1e-3 and impulses 1e-2 (K-products) | "
          "its velocity / impulse error | defaults: K-products, velocity, impulse |")
    print("|---|---|---|---|---|")
    for name, rows in states:
        default = [r for r in rows if r["setting"] == DEFAULT]
        for fam in FAMILIES:
            if not any(r["family"] == fam for r in rows):
                continue  # not in this study's grid
            ok = [r for r in rows if r["family"] == fam and r["setting"] != DEFAULT
                  and r["velocity"] <= 1e-3 and r["impulse"] <= 1e-2]
            best = min(ok, key=lambda r: r["k_products"]) if ok else None
            d = default[0] if default and fam == "pgs-tol" else None
            print("| %s | %s | %s | %s | %s |" % (
                name, fam,
                "%.0f (%s)" % (best["k_products"], best["setting"]) if best else "not reached",
                "%.1e / %.1e" % (best["velocity"], best["impulse"]) if best else "",
                "%.0f, %.1e, %.1e" % (d["k_products"], d["velocity"], d["impulse"]) if d else ""))
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib not available: no picture")
        return
    cols = min(4, len(states))
    rows_n = math.ceil(len(states) / cols)
    fig, axes = plt.subplots(rows_n, cols, figsize=(4.2 * cols, 3.6 * rows_n), squeeze=False)
    styles = {"pgs": "o-", "nncg": "s-", "fbgs": "d-", "apgd": "x-", "cg": "^-", "cg+nncg": "v-",
              "pgs-tol": "P-", "cg-tol": "X-", "nncg-tol": "*-", "fbgs-tol": "D-", "apgd-tol": "+-"}
    for ax, (name, rows) in zip(axes.flat, states):
        for fam in FAMILIES:
            pts = sorted((r["k_products"], r["velocity"]) for r in rows
                         if r["family"] == fam and r["setting"] != DEFAULT and r["velocity"] > 0)
            if pts:
                ax.loglog([x for x, _ in pts], [y for _, y in pts], styles[fam], ms=3, label=fam,
                          color="C%d" % (FAMILIES.index(fam) % 10))  # one colour a family
        for r in rows:
            if r["setting"] == DEFAULT:
                ax.loglog([r["k_products"]], [r["velocity"]], "k*", ms=10, label="defaults")
        ax.axhline(1e-3, color="grey", lw=0.8, ls="--")
        ax.axvline(40, color="grey", lw=0.8, ls=":")
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("cost (K-product equivalents)")
        ax.set_ylabel("velocity-change error")
        ax.grid(True, which="both", lw=0.3)
    for ax in list(axes.flat)[len(states):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)
    print("wrote " + args.png)


if __name__ == "__main__":
    main()
