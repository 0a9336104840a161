"""Janssen scene (examples/janssen): wall pressure with depth in a tall bin, against the native
twin of the same material.

Runs examples/janssen/in.janssen (fix fibre_contact, compliance material) and its native twin
in.janssen.native with seeds 4767, 1031 and 2203: 2,560 spheres filled in 4 batches into an
8 x 8 bin with friction on the walls, settled for 12 s, then 10 snapshots over 1 s. Checks:
- the Janssen effect in both twins: the side walls carry part of the weight by friction, the
  floor less than 80% of it (measured 0.67 and 0.68);
- the fix's wall loads (f_fc[w][3]) balance the weight: the side walls' and the floor's z loads,
  averaged over the snapshots' run, within 3% of the weight (a static pack);
- against the native twin: Janssen's saturation pressure p_sat (the fit of
  p_sat (1 - exp(-(h - z) / lambda)) to the side-wall pressure by height, examples/janssen/
  janssen.py), the deep pressure and the floor's share, each the mean of the three seeds,
  within 10%. Measured (examples/README.md, "Janssen bin"): 1.036, 0.957 and 0.966 of
  native's. One seed's p_sat scatters by about 9% (standard deviation; fibre 32.8 to 41.9
  over nine runs), so two seeds' mean moved from 1.075 to 1.118 of native's with round-off
  alone: three seeds, the target's own measurement, are compared.
- on two processes (seed 4767, the fix only), against the serial run of the same seed: the
  walls' loads, summed over the processes, still balance the weight within 3%, the floor
  carries less than 80% of it, the deep pressure is within 10% and p_sat within 30% (the
  trajectories part at round-off, and the fitted p_sat scatters by about 9% a run: a check
  against gross errors). Seed 4767's p_sat sits high (46.0 serial, 1.28 of native's mean), so
  the serial run of the same seed is the reference, not native's mean. Measured: np 2 against
  serial, deep 32.00 against 31.96, p_sat 47.9 against 46.0.
"""

import argparse
import os
import sys

import fibre_e2e as e2e

SEEDS = (4767, 1031, 2203)


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("scene: janssen bin, fibre (compliance material) against native")
    e2e.copy_scene(args.source, "janssen", args.workdir)
    sys.path.insert(0, args.workdir)
    import janssen  # examples/janssen/janssen.py, copied with the scene

    results = {}
    serial = None  # the fix's run of SEEDS[0], the parallel run's reference
    for seed in SEEDS:
        run_args = argparse.Namespace(**vars(args))
        run_args.workdir = os.path.join(args.workdir, "seed%d" % seed)
        os.makedirs(run_args.workdir, exist_ok=True)
        e2e.copy_scene(args.source, "janssen", run_args.workdir)
        for method, name in (("fibre", "in.janssen"), ("native", "in.janssen.native")):
            measured = run_twin(run_args, ck, janssen, seed, method, name)
            if measured:
                results.setdefault(method, []).append(measured)
                if method == "fibre" and seed == SEEDS[0]:
                    serial = measured
    parallel = None
    if args.mpirun:
        run_args = argparse.Namespace(**vars(args))
        run_args.workdir = os.path.join(args.workdir, "np2")
        os.makedirs(run_args.workdir, exist_ok=True)
        e2e.copy_scene(args.source, "janssen", run_args.workdir)
        parallel = run_twin(run_args, ck, janssen, SEEDS[0], "fibre", "in.janssen", np=2)
    if all(len(results.get(m, [])) == len(SEEDS) for m in ("fibre", "native")):
        mean = {m: {key: sum(r[key] for r in results[m]) / len(SEEDS)
                    for key in ("p_sat", "deep", "floor_share")} for m in results}
        f, n = mean["fibre"], mean["native"]
        for key, what in (("p_sat", "Janssen's saturation pressure"),
                          ("deep", "deep side-wall pressure"), ("floor_share", "floor's share")):
            ratio = f[key] / n[key]
            ck.check(abs(ratio - 1.0) < 0.10, "%s within 10%% of native (mean of seeds %s)"
                     % (what, ", ".join(str(s) for s in SEEDS)),
                     "fibre %.3f, native %.3f (ratio %.3f)" % (f[key], n[key], ratio))
    if parallel and serial:
        for key, what, bound in (("deep", "deep side-wall pressure", 0.10),
                                 ("p_sat", "Janssen's saturation pressure", 0.30)):
            ratio = parallel[key] / serial[key]
            ck.check(abs(ratio - 1.0) < bound, "np 2: %s within %d%% of the serial run of seed %d"
                     % (what, round(100 * bound), SEEDS[0]), "np 2 %.3f, serial %.3f (ratio %.3f)"
                     % (parallel[key], serial[key], ratio))
    ck.close()


def run_twin(args, ck, janssen, seed, method, name, np=1):
    with open(os.path.join(args.workdir, name)) as f:
        deck = f.read()
    run = e2e.run_lmp(args, deck, method, np=np, variables={"seed": seed})
    tag = "%s, seed %d%s" % (method, seed, ", np %d" % np if np > 1 else "")
    if not ck.ran(run, "%s: janssen deck completes" % tag):
        return None
    measured = janssen.measure(args.workdir, method)
    share = measured["floor_share"]
    ck.check(share < 0.8, "%s: the side walls carry part of the weight (floor < 80%%)" % tag,
             "floor / weight = %.3f" % share)
    if method == "fibre":
        snaps = janssen.side_forces(args.workdir, "fibre")
        weight = snaps[-1][3]
        rows = run.thermo[-1]
        load = sum(-(r["f_fc[1][3]"] + r["f_fc[2][3]"] + r["f_fc[3][3]"]) for r in rows)
        load /= len(rows)
        ck.check(abs(load / weight - 1.0) < 0.03,
                 "%s: the walls' z loads balance the weight within 3%%" % tag,
                 "mean load %.1f N, weight %.1f N" % (load, weight))
    return measured


if __name__ == "__main__":
    main()
