"""The global vector describes the step it was computed on, also when a step has no contacts.

A sphere rests on the floor for 20 steps (one contact, a solve, sweeps forced by a tiny
sweep_tol so that f_ID[13..15] are non-zero), then is launched upward: from its second step
in the air there is no contact anywhere, and every solver figure (iterations, residual,
passes, setup/solve/sweep times, complementarity, sweeps) must read 0 and converged 1, not
the last solve's values (before the fix the sweep figures kept the last solve's values). Serial and on two processes.
"""

import os
import re

import fibre_e2e as e2e

DECK = """atom_style sphere
boundary p p f
comm_modify vel yes
region box block -2 2 -2 2 0 20 units box
create_box 1 box
create_atoms 1 single 0.3 -0.2 0.5 units box
set type 1 diameter 1.0 density 1.0
pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0
pair_coeff * *
neighbor 0.2 bin
timestep 0.001
fix g all gravity 9.81 vector 0 0 -1
fix fc all fibre_contact mu 0.5 sweep_tol 1e-14 wall zplane 0.0 NULL
thermo_style custom step f_fc[1] f_fc[2] f_fc[3] f_fc[6] f_fc[8] f_fc[9] f_fc[10] f_fc[13] &
  f_fc[14] f_fc[15] f_fc[16]
thermo_modify format float %.10g
thermo 1
run 20
velocity all set 0 0 5 units box
run 20
"""

SOLVER_FIGURES = ["f_fc[1]", "f_fc[2]", "f_fc[6]", "f_fc[8]", "f_fc[9]", "f_fc[13]", "f_fc[14]",
                  "f_fc[15]", "f_fc[16]"]


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("output: the global vector on steps without contacts")
    for np in (1, 2):
        tag = "np%d" % np
        run = e2e.run_lmp(args, DECK, "output_" + tag, np=np)
        if not ck.ran(run):
            continue
        rest, air = run.thermo[0], run.thermo[1]
        resting = rest[1:]  # step 0 is setup, before any solve
        ck.check(all(r["f_fc[3]"] == 1 and r["f_fc[15]"] > 0 for r in resting),
                 "%s: at rest: one contact, sweep time reported" % tag,
                 "contacts %s, sweep time %.3g s" % (sorted({r["f_fc[3]"] for r in resting}),
                                                     resting[-1]["f_fc[15]"]))
        ck.check(all(r["f_fc[14]"] > 0 for r in resting),
                 "%s: at rest: sweeps reported" % tag,
                 "sweeps %g, residual %.3g" % (resting[-1]["f_fc[14]"],
                                               resting[-1]["f_fc[13]"]))
        free = [r for r in air if r["f_fc[3]"] == 0]
        ck.check(len(free) >= 15, "%s: in the air: no contacts" % tag,
                 "%d of %d lines" % (len(free), len(air)))
        stale = [(r["Step"], k, r[k]) for r in free for k in SOLVER_FIGURES if r[k] != 0]
        ck.check(not stale and all(r["f_fc[10]"] == 1 for r in free),
                 "%s: in the air: every solver figure 0, converged 1" % tag,
                 "stale: %s" % stale[:4] if stale else "")
    # defaults: the log line equals the doc page's "Default" line
    with open(os.path.join(args.source, "doc", "fix_fibre_contact.md")) as f:
        doc = re.search(r"^fix fibre_contact: form .*$", f.read(), re.M)
    deck = DECK.replace("fix fc all fibre_contact mu 0.5 sweep_tol 1e-14 wall zplane 0.0 NULL",
                        "fix fc all fibre_contact").replace("run 20\nvelocity", "velocity")
    run = e2e.run_lmp(args, deck, "output_defaults")
    logged = re.search(r"^fix fibre_contact: form .*$", run.log, re.M)
    ck.check(run.rc == 0 and doc and logged and logged.group(0) == doc.group(0),
             "the logged default settings are the doc page's",
             "log: %s" % (logged.group(0) if logged else None))
    ck.close()


if __name__ == "__main__":
    main()
