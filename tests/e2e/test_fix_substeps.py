"""Substeps (substeps auto): a head-on pair of stiff spheres at a step of five collision times.

The material deck's law at E = 1e8 (examples/material/in.headon: Hertz, Tsuji damping), no
gravity, each sphere at v towards the other, at the decks' step of 4.43 ms (5 t_c):
- native LAMMPS (fix nve/sphere at 2e-5 s, lmp_fibre as a drop-in) rebounds at its law's
  e (0.232 at 1 m/s, 0.234 at 0.05 m/s);
- the fix with substeps auto takes 16 substeps of 0.31 t_c (the log says so) and rebounds
  within 5% of native's e at 1 m/s (Newton's law at the substep that closes) and within 12% at
  0.05 m/s, below the automatic bounce speed, where the compliant rows resolve the collision
  (one solve a step, substeps 1, stops that pair dead, and the log warns of the step);
- on two processes (one sphere on each) the rebounds are the serial ones within 1e-6.
"""

import os
import re
import shutil

import fibre_e2e as e2e

E, DT = 1e8, 0.0044343


def headon(args):
    with open(os.path.join(args.source, "examples", "material", "in.headon")) as f:
        return f.read()


def rebound(args, ck, tag, v, np=1, method="fibre", extra=""):
    variables = {"E": E, "v": v, "method": method}
    if extra:
        variables["fc_extra"] = extra
    variables.update({"dt": 2e-5, "n": 8000} if method == "native" else {"dt": DT, "n": 60})
    run = e2e.run_lmp(args, headon(args), "headon_" + tag, np=np, variables=variables)
    if not ck.ran(run):
        return None, run
    return run.last("v_e"), run


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("substeps: a stiff head-on pair at a step of five collision times")
    for v, tol in ((1.0, 0.05), (0.05, 0.12)):
        native, _ = rebound(args, ck, "native_%g" % v, v, method="native")
        fix, run = rebound(args, ck, "fibre_%g" % v, v)
        fix2, _ = rebound(args, ck, "fibre_np2_%g" % v, v, np=2)
        one, one_run = rebound(args, ck, "single_%g" % v, v, extra="substeps 1")
        if None in (native, fix, fix2, one):
            continue
        ck.check(0.2 < native < 0.26, "v %g: native rebounds at its law's e" % v, "%.4g" % native)
        ck.check(abs(fix - native) < tol * native,
                 "v %g: substeps auto rebounds at native's e within %g%%" % (v, 100 * tol),
                 "%.4g against %.4g" % (fix, native))
        ck.check(abs(fix2 - fix) < 1e-6, "v %g: two processes rebound as one" % v,
                 "%.7g against %.7g" % (fix2, fix))
        found = re.search(r"the contact solve takes (\d+) substeps of (\S+) t_c", run.output)
        ck.check(found is not None and found.group(1) == "16" and float(found.group(2)) <= 0.33,
                 "v %g: the log states 16 substeps of at most 0.33 t_c" % v,
                 found.group(0) if found else "no substeps line")
        if v < 0.1:
            ck.check(one < 0.01, "v %g: one solve a step stops the slow pair dead" % v,
                     "%.3g" % one)
            ck.check("Substeps longer than about a third of t_c" in one_run.output,
                     "v %g: substeps 1 at 5 t_c is warned of in the log" % v)
    plastic_pour(args, ck)
    ck.close()


def plastic_pour(args, ck):
    """The material deck's pour at E = 1e8 without restitution (restitution 0): 15 substeps,
    and no bounce anywhere, so detection must still reach as far as the impacts kick the
    spheres. Before it did, a sphere that a plastic impact at 12.5 m/s kicked in the step's
    first substep ran into a neighbour without a contact, and from step 385 on the overlaps grew
    to 90% of a radius and spheres left the box. Its first 1.8 s (406 steps, 310 spheres)."""
    source = os.path.join(args.source, "examples", "material")
    for name in ("scene.material", "run.material"):
        shutil.copy(os.path.join(source, name), args.workdir)
    with open(os.path.join(source, "in.material")) as f:
        deck = f.read()
    run = e2e.run_lmp(args, deck, "plastic_pour", variables={
        "N": 1400, "E": E, "tend": 1.8, "fc_extra": "restitution 0"})
    if not ck.ran(run):
        return
    rows = [r for b in run.thermo for r in b]
    deepest = max(r["f_fc[7]"] for r in rows)
    ck.check(deepest < 0.0025, "a plastic stiff pour: the deepest overlap stays below 1% of the "
             "smallest radius", "%.3g" % deepest)
    ck.check(rows[-1]["Atoms"] == 310, "a plastic stiff pour: no sphere leaves the box",
             "%d atoms" % rows[-1]["Atoms"])


if __name__ == "__main__":
    main()
