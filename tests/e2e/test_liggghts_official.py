"""LIGGGHTS's public cohesion tutorial and its conversion in examples/official, native against
fix (liggghts_fibre for both twins, through examples/official/official.py).

The tutorial's walls are primitives: two planes and a cylinder (`primitive type 1 zcylinder
0.05 0. 0.`), which become the fix's `wall type 1 zplane 0.0 0.15` and `wall type 1 zcylinder
0.05 0 0`.
- in.noCohesion: all 1000 grains are kept inside the cylinder, and the bed's centre height is
  within 10% of native's; serial and on two processes.
- in.cohesion (`cohesion sjkr`): the fix warns that the cohesion is not modelled, and keeps
  every grain.
"""

import os
import sys

import fibre_e2e as e2e


def main():
    args = e2e.parse_args()
    sys.path.insert(0, os.path.join(args.source, "examples", "official"))
    import official

    ck = e2e.Checks("LIGGGHTS official decks: converted, against native")
    for name, nps in (("cohesion.noCohesion", (1, 2)), ("cohesion.cohesion", (1,))):
        for np in nps:
            wd = os.path.join(args.workdir, "%s.np%d" % (name, np))
            native = official.run_deck(args.lmp, official.native_text(name), wd, "native", np,
                                       args.mpirun)
            fibre = official.run_deck(args.lmp, official.fibre_text(name), wd, "fibre", np,
                                      args.mpirun)
            tag = "%s np %d: " % (name, np)
            if not ck.check(native["rc"] == 0 and fibre["rc"] == 0, tag + "both twins run",
                            "rc %d, %d" % (native["rc"], fibre["rc"])):
                continue
            fn, ff = official.figures(name, native), official.figures(name, fibre)
            ck.check(ff.get("atoms") == fn.get("atoms") == 1000, tag + "every grain kept",
                     "fix %s, native %s" % (ff.get("atoms"), fn.get("atoms")))
            if name == "cohesion.noCohesion":
                ck.check(e2e.rel_err(ff.get("zc", 0), fn.get("zc", 1)) < 0.10,
                         tag + "bed centre height within 10% of native",
                         "%s vs %s" % (ff.get("zc"), fn.get("zc")))
            else:
                ck.check("'cohesion sjkr' is not modelled" in fibre["output"],
                         tag + "the cohesion is warned")
    ck.close()


if __name__ == "__main__":
    main()
