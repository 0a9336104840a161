"""The step's check (keyword check N): the step solved again converged, and the run's errors.

The material deck (examples/material, N 350, E = 1e5, one substep), its first 2 s: the spheres
pour onto the plane. `check 46` solves every 46th step again from the same start, every
substep by projected Gauss-Seidel to an error estimate of 1e-10, and reports the run's
relative errors against it (f_ID[19] the velocity change, f_ID[20] the impulses):
- -1 until the first check with contacts;
- the default step (tol 1e-4) within 1e-3 and above round-off; tol 1e-8 within 1e-6; tol 1e-2
  further off than the default (the check measures the solve, it does not restate it);
- two processes, each with half the pile (the sums over both are global): the same order of
  errors, within 2e-3 at the default and 1e-6 at tol 1e-8.
"""

import os
import re
import shutil

import fibre_e2e as e2e

CHECK = 46  # a multiple of the deck's thermo interval (23 steps)


def deck(args):
    source = os.path.join(args.source, "examples", "material")
    for name in ("scene.material", "run.material"):
        shutil.copy(os.path.join(source, name), args.workdir)
    with open(os.path.join(source, "in.material")) as f:
        text = f.read()
    text = re.sub(r"(?m)^variable\s+fibre_thermo (?:string|index) .*$",
                  'variable  fibre_thermo string "f_fc[3] f_fc[19] f_fc[20]"', text)
    # two processes split the pile (the box is tallest in z, where LAMMPS would cut it)
    return "processors * 1 1\n" + text


def checked(args, ck, tag, extra="", np=1):
    run = e2e.run_lmp(args, deck(args), "check_" + tag, np=np,
                      variables={"N": 350, "tend": 2.0, "fc_extra": "check %d %s" % (CHECK, extra)})
    if not ck.ran(run):
        return None
    rows = [r for b in run.thermo for r in b if int(r["Step"]) % CHECK == 0]
    return [(int(r["Step"]), r["f_fc[3]"], r["f_fc[19]"], r["f_fc[20]"]) for r in rows]


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("check: the step against the converged step")
    runs = {tag: checked(args, ck, tag, extra, np) for tag, extra, np in (
        ("default", "", 1), ("tight", "tol 1e-8", 1), ("loose", "tol 1e-2", 1),
        ("np2", "", 2), ("np2_tight", "tol 1e-8", 2))}
    if None in runs.values():
        return ck.close()
    default = runs["default"]
    first = [row for row in default if row[1] > 0]
    ck.check(default[0][2] == -1 and default[0][3] == -1, "-1 before the first check",
             str(default[0]))
    ck.check(len(first) >= 4, "at least four checks with contacts", str(len(first)))
    worst = {tag: max(max(r[2], r[3]) for r in rows if r[1] > 10) for tag, rows in runs.items()}
    ck.check(1e-8 < worst["default"] < 1e-3, "the default step is within 1e-3 of the converged",
             "%.3g" % worst["default"])
    ck.check(worst["tight"] < 1e-6, "tol 1e-8 is within 1e-6", "%.3g" % worst["tight"])
    ck.check(worst["loose"] > 3 * worst["default"], "tol 1e-2 is further off than the default",
             "%.3g against %.3g" % (worst["loose"], worst["default"]))
    ck.check([r[0] for r in runs["np2"]] == [r[0] for r in default] and
             runs["np2"][0][2:] == (-1.0, -1.0), "two processes check the same steps",
             str([r[0] for r in runs["np2"]]))
    # their sweeps differ from the serial ones (each process sweeps its half, the halos
    # exchange between), so their errors are of the same order, not the same numbers
    ck.check(1e-8 < worst["np2"] < 2e-3, "two processes: the default within 2e-3",
             "%.3g" % worst["np2"])
    ck.check(worst["np2_tight"] < 1e-6, "two processes: tol 1e-8 within 1e-6",
             "%.3g" % worst["np2_tight"])
    return ck.close()


if __name__ == "__main__":
    raise SystemExit(main())
