"""Moving-wall scenes (examples/drum, examples/shear, examples/mixer): short runs of the decks.

Drum (omega 0.6 rad/s, 2 s at rest then 3 s turning), fix fibre_contact serial and on two
processes, and the native twin. Checks: no sphere lost, none through the drum (the largest
distance of a sphere's surface from the axis stays within 5% of the largest diameter of the
radius R = 8), the energy balance over the turning (the drum's work f_fc[17] = kinetic +
potential energy gained + the contacts' take f_fc[18], within 2% of the work), serial and
np 2 agree on the drum's work within 5%, and the bed is lifted as the native twin's is (the
potential energy gained within 10%).
Shear cell (U 2 m/s, 3 s of shear), serial and on two processes, and the native twin: the
effective friction -s_xz / s_zz of the bulk over the last 2 s agrees with native's within 15%
(the examples/README table has the long runs), and the normal stress is positive.
Mixer (blade period 4 s, 1 s at rest, a quarter turn), serial and on two processes, eight
beds each (seeds 11 to 18, the default tol 1e-4): no sphere lost, the energy balance within 2%
of the blade's work, and serial and np 2 agree on the mean work within 10%. The ploughed bed is
chaotic: a 1% change of the stopping rule moves one run's work by up to 14%, so single runs are
no comparison. An ensemble of one bed under four values of tol (0.98 to 1.01
times 1e-4) does not do: with Anderson mixing after every second sweep the steps stop on fewer distinct
sweeps, several of those runs were one, and twelve such runs parted by 13% (serial 13,261,
np 2 15,164) where eight beds part by 5.1% (12,781 and 13,436, standard errors 375 and 442;
mixing after every sweep 13,374 and 12,652).
"""

import os

import fibre_e2e as e2e

R, D_MAX = 8.0, 1.0
TSETTLE, TEND = 2.0, 5.0


def deck(args, name):
    with open(os.path.join(args.workdir, name)) as f:
        return f.read()


def turning(run):
    """Thermo rows of the last run block from the drum's start on."""
    rows = run.thermo[-1]
    return [r for r in rows if r["Time"] >= TSETTLE - 1e-9]


def drum(args, ck):
    gained = {}
    work = {}
    for tag, np_, name in (("fibre_np1", 1, "in.drum"), ("fibre_np2", 2, "in.drum"),
                           ("native", 1, "in.drum.native")):
        run = e2e.run_lmp(args, deck(args, name), "drum_" + tag, np=np_,
                          variables={"omega": 0.6, "tsettle": TSETTLE, "tend": TEND})
        if not ck.ran(run, "drum %s: deck completes" % tag):
            continue
        rows = run.thermo[-1]
        ck.check(all(r["Atoms"] == rows[0]["Atoms"] for r in rows), "drum %s: no sphere lost" % tag,
                 "%g .. %g atoms" % (rows[0]["Atoms"], rows[-1]["Atoms"]))
        reach = max(r["c_rmax"] for r in rows)
        ck.check(reach < R + 0.05 * D_MAX, "drum %s: no sphere through the drum" % tag,
                 "largest r + radius %.4f (R = %g)" % (reach, R))
        ck.check(all(e2e.finite(list(r.values())) for r in rows), "drum %s: thermo finite" % tag)
        a, b = turning(run)[0], rows[-1]
        gained[tag] = b["c_pe"] - a["c_pe"]
        if "f_fc[17]" not in b:
            continue
        w = b["f_fc[17]"] - a["f_fc[17]"]
        taken = b["f_fc[18]"] - a["f_fc[18]"]
        kinetic = (b["c_ke"] + b["c_rot"]) - (a["c_ke"] + a["c_rot"])
        work[tag] = w
        ck.check(w > 0 and abs(w - taken - kinetic - gained[tag]) < 0.02 * w,
                 "drum %s: the drum's work is the energy gained plus the contacts' take" % tag,
                 "work %.6g, kinetic %.6g, potential %.6g, taken %.6g" %
                 (w, kinetic, gained[tag], taken))
    if len(work) == 2:
        ck.agree(work["fibre_np1"], work["fibre_np2"], 0.05,
                 "drum: serial and np 2 agree on the drum's work")
    if "fibre_np1" in gained and "native" in gained:
        ck.agree(gained["fibre_np1"], gained["native"], 0.10,
                 "drum: the bed is lifted as the native twin's (potential energy gained)")


def shear(args, ck):
    mu = {}
    for tag, np_, name in (("fibre_np1", 1, "in.shear"), ("fibre_np2", 2, "in.shear"),
                           ("native", 1, "in.shear.native")):
        run = e2e.run_lmp(args, deck(args, name), "shear_" + tag, np=np_,
                          variables={"U": 2.0, "tshear": 3.0})
        if not ck.ran(run, "shear %s: deck completes" % tag):
            continue
        rows = run.thermo[-1]
        t0 = rows[0]["Time"]
        late = [r for r in rows if r["Time"] - t0 >= 1.0]
        mu[tag] = sum(r["v_muw"] for r in late) / len(late)
        p = sum(r["v_pzz"] for r in late) / len(late)
        ck.check(p > 0, "shear %s: the bulk is under compression" % tag, "mean s_zz %.4g Pa" % p)
    for tag in ("fibre_np1", "fibre_np2"):
        if tag in mu and "native" in mu:
            ck.agree(mu[tag], mu["native"], 0.15,
                     "shear %s: effective friction as the native twin's" % tag, "%.4f")


def mixer(args, ck):
    # A ploughed bed is chaotic: a quarter turn's work scatters by about 9% between beds
    # (standard deviation over eight seeds), so one serial and one np 2 run can part by 14%.
    # The runs are compared as ensembles of eight beds per process count, the means within 10%
    # (measured 5.1%; the standard error of the difference is about 4.5%).
    work = {}
    for tag, np_ in (("np1", 1), ("np2", 2)):
        work[tag] = []
        for seed in range(11, 19):
            run = e2e.run_lmp(args, deck(args, "in.mixer"), "mixer_%s_%d" % (tag, seed), np=np_,
                              variables={"period": 4.0, "tsettle": 1.0, "revs": 0.25,
                                         "seed": seed, "fc_extra": "compliance material"})
            if not ck.ran(run, "mixer %s, seed %d: deck completes" % (tag, seed)):
                continue
            a, b = run.thermo[-1][0], run.thermo[-1][-1]
            ck.check(b["Atoms"] == a["Atoms"], "mixer %s: no sphere lost" % tag,
                     "%g -> %g atoms" % (a["Atoms"], b["Atoms"]))
            w = b["f_fc[17]"] - a["f_fc[17]"]
            taken = b["f_fc[18]"] - a["f_fc[18]"]
            gained = (b["c_ke"] + b["c_rot"] + b["c_pe"]) - (a["c_ke"] + a["c_rot"] + a["c_pe"])
            work[tag].append(w)
            ck.check(w > 0 and abs(w - taken - gained) < 0.02 * w,
                     "mixer %s: the blade's work is the energy gained plus the contacts' take"
                     % tag, "work %.6g, gained %.6g, taken %.6g" % (w, gained, taken))
    if work["np1"] and work["np2"]:
        means = [sum(work[t]) / len(work[t]) for t in ("np1", "np2")]
        ck.agree(means[0], means[1], 0.10,
                 "mixer: serial and np 2 agree on the blade's mean work over eight beds")


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("scenes: drum and shear cell")
    e2e.copy_scene(args.source, "drum", args.workdir)
    e2e.copy_scene(args.source, "shear", args.workdir)
    e2e.copy_scene(args.source, "mixer", args.workdir)
    drum(args, ck)
    shear(args, ck)
    mixer(args, ck)
    ck.close()


if __name__ == "__main__":
    main()
