"""The comparison tool's silo analysis (examples/compare/compare.py steady_rate) on discharge
curves with known answers, no LAMMPS run:

- a steady flow of 10 kg/s: the rate to 1e-9, not clogged;
- a flow that stops for good with mass left: clogged;
- a flow held by an arch that lets a sphere through now and then (0.05 kg every 0.5 s, as
  seed 1031 of the D = 3.5 silo did): clogged;
- a flow that arches for 1 s and runs on: not clogged;
- a silo that runs empty: not clogged;
- the seeds' statistics (paired_stats): each twin's mean, range and spread over its own
  seeds, the difference paired by seed with its standard error, a clogged seed (NaN) and a
  seed one twin lacks left out of the pairs, and the difference of the twins' own means with
  its standard error, against values worked out by hand;
- a former seeds table read back (read_seeds_table, for `seeds --from-table`): each twin's
  figures per seed, clogged as NaN, the statistics rows left out.
"""

import math
import os
import sys
import tempfile

import numpy as np

import fibre_e2e as e2e


def curve(rates, m0=200.0, dt=0.1):
    """m(t) from a rate per 0.5 s window, opened at t = 0, never below 0."""
    t = np.arange(0.0, 0.5 * len(rates) + 1e-9, dt)
    m = np.empty_like(t)
    for k, tk in enumerate(t):
        out = 0.0
        for w, rate in enumerate(rates):
            out += rate * min(max(tk - 0.5 * w, 0.0), 0.5)
        m[k] = max(m0 - out, 0.0)
    return t, m


def main():
    args = e2e.parse_args()
    sys.path.insert(0, os.path.join(args.source, "examples", "compare"))
    import compare

    ck = e2e.Checks("compare.py: discharge rate and clogs")
    rate, _, _, clogged = compare.steady_rate(*curve([10.0] * 14))
    ck.check(abs(rate - 10.0) < 1e-9 and not clogged, "steady flow: its rate, no clog",
             "rate %.12g, clogged %s" % (rate, clogged))
    _, _, _, clogged = compare.steady_rate(*curve([10.0] * 8 + [0.0] * 6))
    ck.check(clogged, "a flow that stops with mass left is clogged")
    _, _, _, clogged = compare.steady_rate(*curve([10.0] * 8 + [0.1, 0.0, 0.6, 0.0, 0.1, 0.0]))
    ck.check(clogged, "an arch that lets a sphere through now and then is a clog")
    _, _, _, clogged = compare.steady_rate(*curve([10.0] * 6 + [0.0, 0.0] + [10.0] * 6))
    ck.check(not clogged, "an arch that breaks again is no clog")
    _, _, _, clogged = compare.steady_rate(*curve([40.0] * 14))
    ck.check(not clogged, "a silo that runs empty is no clog")

    nan = float("nan")
    st = compare.paired_stats({"1": 5.0, "2": 5.2, "3": 4.9, "4": nan},
                              {"1": 4.8, "2": 5.0, "3": 4.8, "5": 4.7})
    # pairs 1..3: differences 0.2, 0.2, 0.1; sd sqrt(1/300), se 1/30; native there 4.8667
    ck.check(st["paired"] == 3 and abs(st["diff"] - 0.5 / 3) < 1e-12
             and abs(st["diff_se"] - 1.0 / 30) < 1e-12, "paired difference and its error",
             "%s" % st)
    ck.check(abs(st["rel"] - 0.5 / 14.6) < 1e-12 and abs(st["rel_se"] - 0.1 / 14.6) < 1e-12,
             "the difference relative to native's mean over the pairs", "%s" % st)
    f, n = st["fibre"], st["native"]
    ck.check(f["n"] == 3 and abs(f["mean"] - 15.1 / 3) < 1e-12 and f["min"] == 4.9
             and f["max"] == 5.2 and n["n"] == 4 and abs(n["mean"] - 4.825) < 1e-12
             and abs(n["sd"] - 0.125830573921179) < 1e-12, "each twin over its own seeds",
             "%s" % st)
    # the means: 15.1 / 3 - 4.825 = 5 / 24; variances 7 / 300 (3 seeds) and 19 / 1200 (4), so
    # the error is sqrt(7 / 900 + 19 / 4800) = 13 / 120
    ck.check(abs(st["means"] - 5.0 / 24) < 1e-12 and abs(st["means_se"] - 13.0 / 120) < 1e-12
             and abs(st["means_rel"] - 5.0 / 24 / 4.825) < 1e-12
             and abs(st["means_rel_se"] - 13.0 / 120 / 4.825) < 1e-12,
             "the difference of the twins' own means and its error", "%s" % st)

    silo = ("silo, N 1400, 3 seeds\n\n"
            "| seed | native discharge rate (kg/s) | native wall s / simulated s "
            "| fibre discharge rate (kg/s) | fibre wall s / simulated s |\n"
            "|---|---|---|---|---|\n"
            "| 4767 | 13.57 | 30.20 | 11.16 | 5.44 |\n"
            "| 1031 | clogged | 46.98 | 12.67 | 5.37 |\n"
            "| 3037 | 12.72 | 44.70 | clogged | 2.67 |\n\n"
            "| figure | native: mean (range), sd | fix: mean (range), sd | fix - native | means |\n"
            "|---|---|---|---|---|\n"
            "| discharge rate (kg/s) | 13.1 (12.7..13.6), 0.6, 2 seeds | 11.9 | -9.3% | -9.3% |\n")
    with tempfile.NamedTemporaryFile("w", suffix=".md", delete=False) as f:
        f.write(silo)
    try:
        t = compare.read_seeds_table(f.name, "silo")
    finally:
        os.unlink(f.name)
    ck.check(sorted(t["native"]["rate"]) == ["1031", "3037", "4767"]
             and t["native"]["rate"]["4767"] == 13.57 and t["fibre"]["rate"]["1031"] == 12.67
             and t["native"]["wall_per_s"]["1031"] == 46.98
             and t["fibre"]["wall_per_s"]["3037"] == 2.67
             and math.isnan(t["native"]["rate"]["1031"]) and math.isnan(t["fibre"]["rate"]["3037"]),
             "a seeds table read back: each twin per seed, clogged as NaN", "%s" % t)
    ck.close()


if __name__ == "__main__":
    main()
