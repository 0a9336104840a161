"""Silo scene (examples/silo): a short fill and discharge of the shipped decks.

Runs examples/silo/in.silo (fix fibre_contact) with N = 350 and orifice D = 4: the emitter
inserts all 350 spheres in one batch, they fall into the plugged funnel for TFILL seconds,
then the plug is removed (the funnel region is redefined) and they flow for TFLOW seconds.
Serial, and the native twin in.silo.native. Checks: 350 inserted and none lost while
plugged, thermo finite, the deepest overlap: over every step (f_fc[7], walls included) below
Hertz's overlap of the largest sphere hitting the wall at the free-fall speed from the
emitter's top, and in the filled funnel at most 1.5x the native twin's there (the deck's
pair_coeff is the material of both: soft Hertz, E = 1e5), the complementarity residual of every sampled step (f_fc[13]) below 1e-2,
every sphere inside the funnel before opening (within 10% of d_min: none below the plug or
outside the orifice), mass
leaves through the orifice after opening. Then a short fill (0.3 s) serial and on two
processes (np 2 is slow on an oversubscribed machine): both complete, insert all 350, and
agree on the kinetic energy within 5%.
"""

import math
import os

import fibre_e2e as e2e

N, D, TFILL, TFLOW = 350, 4.0, 3.0, 1.5
# scene.silo's material and geometry: E, nu, density, the largest radius, the emitter's top
E, NU, RHO, R_MAX, Z_EMIT = 1.0e5, 2.0 / 7.0, 1.0, 0.5, 34.0


def hertz_impact_overlap():
    """The deepest overlap of a sphere of radius R_MAX hitting a wall head on at the speed of
    a fall from Z_EMIT (1/2 m v^2 = 2/5 k_n sqrt(R) d^(5/2), k_n = 4/3 E / (2 (1 - nu^2)),
    the pair's constants that the fix gives its walls)."""
    m = RHO * 4.0 / 3.0 * math.pi * R_MAX ** 3
    v2 = 2 * 9.81 * Z_EMIT
    k_n = 4.0 / 3.0 * E / (2 * (1 - NU * NU))
    return (5 * m * v2 / (4 * k_n * math.sqrt(R_MAX))) ** 0.4


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("scene: silo, N %d, D %g" % (N, D))
    e2e.copy_scene(args.source, "silo", args.workdir)
    out, filled_overlap = {}, {}
    for tag, np_, name in (("serial", 1, "in.silo"), ("native", 1, "in.silo.native")):
        with open(os.path.join(args.workdir, name)) as f:
            deck = f.read()
        run = e2e.run_lmp(args, deck, "silo_" + tag, np=np_,
                          variables={"N": N, "D": D, "tfill": TFILL, "tflow": TFLOW})
        if not ck.ran(run, "%s: silo deck completes" % tag):
            continue
        fill, flow = run.thermo[0], run.thermo[1]
        ck.check(fill[-1]["Atoms"] == N, "%s: %d spheres inserted, none lost while plugged"
                 % (tag, N), "%g atoms" % fill[-1]["Atoms"])
        ck.check(all(e2e.finite(list(r.values())) for r in fill + flow), "%s: thermo finite" % tag)
        if "f_fc[7]" in fill[-1]:
            worst, bound = max(r["f_fc[7]"] for r in fill + flow), hertz_impact_overlap()
            ck.check(worst < bound, "%s: deepest overlap below Hertz's at the largest impact"
                     % tag, "max f_fc[7] = %.3g, Hertz %.3g" % (worst, bound))
            compl = max(r["f_fc[13]"] for r in fill + flow)
            ck.check(compl < 1e-2, "%s: complementarity residual below 1e-2" % tag,
                     "max f_fc[13] = %.2g" % compl)
        method = "native" if tag == "native" else "fibre"
        filled = os.path.join(args.workdir, "silo.%s.%d.filled.dump" % (method, N))
        frame = e2e.parse_dump(filled)[-1]
        filled_overlap[tag] = e2e.deepest_overlap([frame])
        atoms = e2e.dump_by_id(frame)
        low = min(a["z"] - a["radius"] for a in atoms.values())
        wide = max(math.hypot(a["x"], a["y"]) + a["radius"] for a in atoms.values()
                   if a["z"] < 4.0) if any(a["z"] < 4.0 for a in atoms.values()) else 0.0
        ck.check(low > -0.05 and wide < D / 2 + 0.05, "%s: plugged funnel holds the spheres"
                 % tag, "lowest sphere bottom %.3g, widest in the orifice %.3g" % (low, wide))
        gone = flow[0]["v_mass"] - flow[-1]["v_mass"]
        ck.check(gone > 0.05 * flow[0]["v_mass"], "%s: discharge after opening" % tag,
                 "%.3g of %.3g kg left the silo in %.1f s" % (gone, flow[0]["v_mass"], TFLOW))
        out[tag] = gone
        os.replace(filled, filled + "." + tag)
    if len(filled_overlap) == 2:
        ck.check(0 < filled_overlap["serial"] <= 1.5 * filled_overlap["native"],
                 "filled funnel: deepest overlap at most 1.5x the native twin's",
                 "%.3g, native %.3g" % (filled_overlap["serial"], filled_overlap["native"]))
    ke = {}
    with open(os.path.join(args.workdir, "in.silo")) as f:
        deck = f.read()
    for tag, np_ in (("short_serial", 1), ("short_np2", 2)):
        run = e2e.run_lmp(args, deck, "silo_" + tag, np=np_,
                          variables={"N": N, "D": D, "tfill": 0.3, "tflow": 0.05})
        if ck.ran(run, "%s: silo deck completes" % tag):
            last = run.thermo[0][-1]
            ck.check(last["Atoms"] == N, "%s: %d inserted" % (tag, N), "%g" % last["Atoms"])
            ke[tag] = last["c_ke"]
    if len(ke) == 2:
        ck.agree(ke["short_serial"], ke["short_np2"], 0.05,
                 "serial and np 2 agree on the kinetic energy")
    if "serial" in out and "native" in out:
        print("info: discharged mass fibre %.4g kg, native %.4g kg" % (out["serial"], out["native"]))
    ck.close()


if __name__ == "__main__":
    main()
