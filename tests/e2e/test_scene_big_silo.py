"""The production-sized silo (examples/big_silo) at a small size: the same deck and script at
R = 10, H = 20 (a few thousand spheres instead of 204,410), fix fibre_contact serially and on
two processes, and its native twin. Checks: every run ends; no sphere leaves while the
orifice is plugged, and once it is open some leave; the settled bed's centre within 1% of
native's and on two processes within 0.5% of serial; the discharge rate (a line fitted to the
spheres above the floor) within 25% of native's and of serial's (about 120 spheres leave: one
sphere more or less is 1%); the deepest overlap of the discharge below 15% of a diameter.
"""

import os
import sys

import fibre_e2e as e2e

SIZE = dict(R=10, H=20, Do=6.0, tsettle=1.2, tflow=1.0, tskip=0.3)


def main():
    args = e2e.parse_args()
    sys.path.insert(0, os.path.join(args.source, "examples", "big_silo"))
    import big_silo

    ck = e2e.Checks("scene: the big silo at R %g, H %g" % (SIZE["R"], SIZE["H"]))
    lmp = os.path.abspath(args.lmp)
    wd = os.path.abspath(args.workdir)
    fix = big_silo.run(lmp, "fibre", os.path.join(wd, "fibre"), 1, **SIZE)
    native = big_silo.run(lmp, "native", os.path.join(wd, "native"), 1, **SIZE)
    pair = big_silo.run(lmp, "fibre", os.path.join(wd, "np2"), 2, **SIZE)
    if not ck.check(fix and native and pair, "the three runs end"):
        ck.close()
        return
    for name, r in (("fix", fix), ("native", native), ("fix on two processes", pair)):
        ck.check(r["spheres"] == native["spheres"] > 2000, "%s: the same spheres" % name,
                 "%d" % r["spheres"])
        ck.check(r["settled"] == r["spheres"], "%s: none leaves while the orifice is plugged"
                 % name, "%d of %d" % (r["settled"], r["spheres"]))
        ck.check(r["spheres"] - r["inside"] > 20, "%s: spheres leave through the orifice" % name,
                 "%d of %d above the floor, %d in the box" % (r["inside"], r["spheres"],
                                                               r["left"]))
    ck.check(e2e.rel_err(fix["zcm"], native["zcm"]) < 0.01,
             "settled bed's centre within 1% of native's", "%.4f vs %.4f" % (fix["zcm"],
                                                                            native["zcm"]))
    ck.check(e2e.rel_err(pair["zcm"], fix["zcm"]) < 0.005,
             "two processes: settled bed's centre within 0.5% of serial's",
             "%.4f vs %.4f" % (pair["zcm"], fix["zcm"]))
    ck.check(e2e.rel_err(fix["rate"], native["rate"]) < 0.25,
             "discharge rate within 25% of native's", "%.1f vs %.1f spheres / s"
             % (fix["rate"], native["rate"]))
    ck.check(e2e.rel_err(pair["rate"], fix["rate"]) < 0.25,
             "two processes: discharge rate within 25% of serial's",
             "%.1f vs %.1f spheres / s" % (pair["rate"], fix["rate"]))
    ck.check(fix["overlap"] < 0.15 * 0.90 and pair["overlap"] < 0.15 * 0.90,
             "deepest overlap of the discharge below 15% of the smallest diameter",
             "%.3f and %.3f" % (fix["overlap"], pair["overlap"]))
    ck.close()


if __name__ == "__main__":
    main()
