"""The official LAMMPS decks converted to fix fibre_contact, shortened.

examples/granregion/in.granregion.funnel.fibre and examples/pour/in.pour.fibre.full are run
from a copy in which only the particle count (`fix ins all pour`), the `run` lengths and, so
that the particles meet each other and the walls within a short run, gravity (funnel: 4
instead of 1) or the insertion slab (pour: 1..6 instead of 10..15) are changed; the funnel
copy also gets `compute_modify thermo_temp dynamic/dof yes` (the original's `ke` column is
-0 throughout: its temperature keeps the degrees of freedom of the empty box). Everything else is kept: LAMMPS's balance commands, multi
neighbor lists, the region redefinition that opens the funnel, the chute gravity.

Serial, longer: the funnel fills and drains through the opened cylinder, the pour lands on
the floor. Checks: completion, the particles inserted, thermo finite, contacts found, the
deepest overlap (f_1[7]) bounded. Serial and on two processes, short (np 2 is slow on an
oversubscribed machine): completion, the count, and serial/np 2 agreement on the kinetic
energy within 5%.
"""

import os
import re

import fibre_e2e as e2e


def shortened(path, count, runs, subs=()):
    with open(path) as f:
        text = f.read()
    text = re.sub(r"(fix\s+ins\s+all\s+pour\s+)\d+", r"\g<1>%d" % count, text)
    for a, b in subs:
        assert a in text, "%r not in %s" % (a, path)
        text = text.replace(a, b)
    lines, k = [], 0
    for line in text.splitlines():
        if re.match(r"^run\s+\d+", line):
            line = "run %d" % runs[k]
            k += 1
        lines.append(line)
    assert k == len(runs), "expected %d run commands in %s, found %d" % (len(runs), path, k)
    return "\n".join(lines) + "\n"


FUNNEL_SUBS = [("variable	gravity equal 1.0", "variable	gravity equal 4.0"),
               # the original's 'ke' stays -0: its temperature has the dof of the empty box
               ("thermo_modify	flush yes lost warn",
                "thermo_modify	flush yes lost warn\ncompute_modify	thermo_temp dynamic/dof yes")]
POUR_SUBS = [("region		slab block -9.0 9.0 -9.0 9.0 10.0 15.0",
              "region		slab block -9.0 9.0 -9.0 9.0 1.0 6.0")]


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("official decks converted: granregion funnel, pour")
    src = args.source
    funnel_path = os.path.join(src, "examples", "granregion", "in.granregion.funnel.fibre")
    pour_path = os.path.join(src, "examples", "pour", "in.pour.fibre.full")

    # serial, longer: the physics
    run = e2e.run_lmp(args, shortened(funnel_path, 150, [1500, 300, 1200], FUNNEL_SUBS),
                      "funnel_long")
    if ck.ran(run, "funnel: completes (fill, settle, open, drain)"):
        fill, settle, drain = run.thermo
        rows = fill + settle + drain
        ck.check(fill[-1]["Atoms"] == 150, "funnel: 150 inserted", "%g" % fill[-1]["Atoms"])
        ck.check(all(e2e.finite(list(r.values())) for r in rows), "funnel: thermo finite")
        ck.check(settle[-1]["f_1[3]"] > 50, "funnel: spheres rest on each other and the hopper",
                 "%g contacts" % settle[-1]["f_1[3]"])
        worst = max(r["f_1[7]"] for r in rows)
        ck.check(worst < 0.02 * 0.5, "funnel: deepest overlap below 2% of d_min", "%.3g" % worst)
        ck.check(drain[-1]["Atoms"] < 150, "funnel: the opened hopper drains",
                 "%g of 150 left" % drain[-1]["Atoms"])
    run = e2e.run_lmp(args, shortened(pour_path, 300, [400, 100], POUR_SUBS), "pour_long")
    if ck.ran(run, "pour: completes (pour, chute)"):
        pour, chute = run.thermo
        ck.check(pour[-1]["Atoms"] == 300, "pour: 300 inserted", "%g" % pour[-1]["Atoms"])
        ck.check(all(e2e.finite(list(r.values())) for r in pour + chute), "pour: thermo finite")
        ck.check(pour[-1]["f_1[3]"] > 100, "pour: particles on the floor and each other",
                 "%g contacts" % pour[-1]["f_1[3]"])
        worst = max(r["f_1[7]"] for r in pour + chute)
        ck.check(worst < 0.01, "pour: deepest overlap below 1% of d", "%.3g" % worst)

    # serial and np 2, short
    ke = {}
    for tag, np_ in (("serial", 1), ("np2", 2)):
        for name, deck, n in (
                ("funnel", shortened(funnel_path, 60, [60, 10, 10], FUNNEL_SUBS), 60),
                ("pour", shortened(pour_path, 100, [100, 10], POUR_SUBS), 100)):
            run = e2e.run_lmp(args, deck, "%s_short_%s" % (name, tag), np=np_)
            if ck.ran(run, "%s short %s: completes" % (name, tag)):
                last = run.thermo[-1][-1]  # the funnel's first block has KinEng -0 (dof 0)
                ck.check(last["Atoms"] == n, "%s short %s: %d inserted" % (name, tag, n),
                         "%g" % last["Atoms"])
                ke[(name, tag)] = last["KinEng"] if "KinEng" in last else last["c_1"]
    for name in ("funnel", "pour"):
        if (name, "serial") in ke and (name, "np2") in ke:
            ck.agree(ke[(name, "serial")], ke[(name, "np2")], 0.05,
                     "%s: serial and np 2 agree on the kinetic energy" % name)
    ck.close()


if __name__ == "__main__":
    main()
