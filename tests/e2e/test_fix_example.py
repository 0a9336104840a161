"""The README's main example, examples/pour/in.pour.fibre, runs as shipped (serial and on two
processes): it finishes, keeps its 250 particles, pours them into a pile (the kinetic
energy at the end of the pour is below 1% of its peak, overlaps below 1% of the diameter)
and then flows down the chute. Its wall time is reported by ck.ran, not judged (the
machines are noisy; bench/ holds the timings).
"""

import os

import fibre_e2e as e2e


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("example: examples/pour/in.pour.fibre")
    with open(os.path.join(args.source, "examples", "pour", "in.pour.fibre")) as f:
        deck = f.read()
    for np in (1, 2):
        tag = "np%d" % np
        run = e2e.run_lmp(args, deck, "example_pour_" + tag, np=np, timeout=600)
        if not ck.ran(run, "%s: in.pour.fibre runs" % tag):  # its time is reported, not judged
            continue
        pour, chute = run.thermo[0], run.thermo[1]
        values = [v for b in run.thermo for r in b for v in r.values()]
        ck.check(e2e.finite(values) and pour[-1]["Atoms"] == 250 and
                 chute[-1]["Atoms"] == 250, "%s: finite, 250 particles" % tag,
                 "%g atoms at the end" % chute[-1]["Atoms"])
        peak = max(r["KinEng"] for r in pour)
        worst = max(r["f_1[7]"] for r in pour + chute)
        ck.check(pour[-1]["KinEng"] < 0.01 * peak and worst < 0.01,
                 "%s: poured into a pile" % tag,
                 "KE %.3g at the end of the pour (peak %.3g), deepest overlap %.3g"
                 % (pour[-1]["KinEng"], peak, worst))
        ck.check(chute[-1]["KinEng"] > pour[-1]["KinEng"], "%s: flows down the chute" % tag,
                 "KE %.3g -> %.3g" % (pour[-1]["KinEng"], chute[-1]["KinEng"]))
    ck.close()


if __name__ == "__main__":
    main()
