"""The fix at about 2e4 spheres (bench/scale/in.bed: a dense bed W = 22 fcc cells across and
D = 10 deep, 19,360 spheres, settling for 0.5 simulated seconds; bench/scale.py's runs):
- memory: the largest resident set above the same deck's run of 16 spheres, per contact at the
  end, stays within a regression bound (BYTES_PER_CONTACT, the figure measured when the bound
  was set plus 25%; the target is 1 KB, bench/README.md "Scale");
- on two processes against serial: the same spheres, the bed's centre height within 0.5% and
  the contacts within 2% (the processes' sweeps agree to the step's tol, not to round-off).
"""

import os
import sys

import fibre_e2e as e2e

# 2,758 bytes a contact measured when the bound was set (2026-12-05: 90 MB above the small
# run, 32,590 contacts), plus 25%
BYTES_PER_CONTACT = 3450


def main():
    args = e2e.parse_args()
    sys.path.insert(0, os.path.join(args.source, "bench"))
    import scale

    ck = e2e.Checks("scale: memory per contact and two processes at 2e4 spheres")
    lmp = os.path.abspath(args.lmp)
    wd = os.path.abspath(args.workdir)
    base = scale.run(lmp, 1, "fibre", 2, 1, 0.01, False, os.path.join(wd, "base"))
    serial = scale.run(lmp, 1, "fibre", 22, 10, 0.5, False, os.path.join(wd, "np1"))
    pair = scale.run(lmp, 2, "fibre", 22, 10, 0.5, False, os.path.join(wd, "np2"))
    if not ck.check(base and serial and pair, "the three runs end"):
        ck.close()
        return
    per_contact = (serial["rss"] - base["rss"]) / serial["contacts"]
    ck.check(per_contact <= BYTES_PER_CONTACT,
             "resident set per contact within %d bytes" % BYTES_PER_CONTACT,
             "%.0f bytes: %.0f MB above 16 spheres' run, %.0f contacts"
             % (per_contact, (serial["rss"] - base["rss"]) / 1e6, serial["contacts"]))
    ck.check(serial["atoms"] == pair["atoms"] == 19360, "every sphere kept",
             "%d and %d" % (serial["atoms"], pair["atoms"]))
    ck.check(e2e.rel_err(pair["zc"], serial["zc"]) < 0.005,
             "bed centre on two processes within 0.5% of serial",
             "%.6g vs %.6g" % (pair["zc"], serial["zc"]))
    ck.check(e2e.rel_err(pair["contacts"], serial["contacts"]) < 0.02,
             "contacts on two processes within 2% of serial",
             "%.0f vs %.0f" % (pair["contacts"], serial["contacts"]))
    ck.close()


if __name__ == "__main__":
    main()
