"""Clumps (keyword clumps molecule): spheres of one molecule move as one rigid body.

Against analytic mechanics and conservation laws, serially and with a clump split over two
processes:
- a dumbbell of two unit spheres (diameter 1, touching) on a floor under gravity g = 1 tilted
  by 30 degrees. Its axis along the slope: it cannot roll (one sphere would leave the floor),
  so it slides at a = g (sin - mu cos) for mu = 0.3, where each sphere alone would roll at
  5/7 g sin, and sticks for mu = 0.7 > tan 30. Its axis across the slope: it rolls at
  a = 5/7 g sin (its inertia about its axis is its spheres'). Accelerations within 1e-3.
- a free L-shaped clump of four spheres tumbling without gravity (an asymmetric top, whose
  angular velocity wanders): its angular momentum is conserved (1e-9), its energy within 1e-3
  at h omega = 0.01, and its shape within 1e-3 of a diameter (the joints hold it stretched by
  about (h omega)^2 of its size against the centripetal pull: 4.4e-4 here, 100 times less at
  a tenth of the step); it has no contacts.
- a clump of three spheres dropped tumbling onto a floor (pair granular, Hertz with Tsuji
  damping): its kinetic, rotational and potential energy and the contacts' dissipation
  (f_ID[18]) add up to its starting energy within 2e-3 (symplectic Euler's own drift in free
  fall is 7e-4 of it), serially and on two processes, and on two processes with the clump on
  one and a lone sphere dropped on the other (a process whose contacts hold no joint).
- the heap of examples/clumps as it ships (LAMMPS's V-shaped clumps of five spheres, 588 of
  them, dropped onto a floor), against native fix rigid/small with the same pair style and
  walls: no atom lost, the heap's height and spread within 10% and its angle of repose within
  6 degrees. One seed, whose angle is chaotic: the fix's angle for the example's second seed
  was 12.3 to 17.0 degrees under round-off changes of the solve, and over ten seeds the twins'
  differences have a standard deviation of 3.4 degrees, their means -0.7 (standard error 1.0;
  examples/README.md). The band is a guard against a clump that rolls or slides as no rigid
  body would, not the 2 degrees that ten seeds resolve.
- a restart in the middle of the tumbling: the clump is set up again from the positions the
  file holds, its angular momentum kept to 1e-9 and its energy within 1e-3 of the
  uninterrupted run's.
- errors: no molecule IDs, or a bad value, name the keyword.
"""

import math
import os

import fibre_e2e as e2e

THETA = 30.0
YWIDTH, CLUMPS = 24, 588  # the heap: examples/clumps as it ships
DT = 0.01
T1_STEP, T2_STEP = 200, 1000


def clump_opening(box, spheres, cutoff, boundary="f f f", processors=None,
                  law="gran/hooke 1.0 NULL 0.0 NULL 0.0 0", coeff="", dt=DT):
    """The deck's lines up to the step: unit spheres at `spheres` (x, y, z), all of molecule 1
    (fix property/atom), a halo of `cutoff` that reaches across the clump, the pair style."""
    lines = e2e.sphere_box(box, boundary=boundary, processors=processors)
    lines[4] = "comm_modify vel yes cutoff %g" % cutoff
    lines.insert(1, "fix prop all property/atom mol ghost yes")
    lines += ["create_atoms 1 single %g %g %g units box" % p for p in spheres]
    return lines + ["set atom * diameter 1.0 density 1.0", "set atom * mol 1",
                    "pair_style " + law, "pair_coeff * * " + coeff, "neighbor 0.2 bin",
                    "timestep %g" % dt]


def dumbbell_deck(spheres, mu, processors=None):
    t = math.radians(THETA)
    lines = clump_opening("-10 10 -3 3 0 5", [(x, y, 0.5) for x, y in spheres], 2.5,
                          boundary="p p f", processors=processors)
    return "\n".join(lines + [
        "fix g all gravity 1.0 vector %.17g 0 %.17g" % (math.sin(t), -math.cos(t)),
        "fix fc all fibre_contact wall zplane 0.0 NULL mu %g clumps molecule" % mu,
        "compute p all property/atom xu vx omegay",
        "compute s all reduce ave c_p[1] c_p[2] c_p[3]",
        "thermo_style custom step c_s[1] c_s[2] c_s[3] f_fc[3]",
        "thermo_modify format float %.15g",
        "thermo 100",
        "run %d" % T2_STEP,
    ]) + "\n"


# an L of four unit spheres in the xy plane, centre of mass (0.25, 0.75, 0)
L_SPHERES = [(0, 0), (1, 0), (0, 1), (0, 2)]
OMEGA = (0.3, 0.2, 1.0)


def tumbling_deck(steps, processors=None):
    lines = clump_opening("-10 10 -10 10 -10 10", [(x, y, 0) for x, y in L_SPHERES], 3.0,
                          processors=processors)
    wx, wy, wz = OMEGA
    return "\n".join(lines + [
        # the rigid motion omega about the centre of mass
        "variable vx atom %.17g*z-%.17g*(y-0.75)" % (wy, wz),
        "variable vy atom %.17g*(x-0.25)-%.17g*z" % (wz, wx),
        "variable vz atom %.17g*(y-0.75)-%.17g*(x-0.25)" % (wx, wy),
        "velocity all set v_vx v_vy v_vz",
        "set atom * omega %g %g %g" % OMEGA,
        "fix fc all fibre_contact clumps molecule",
        "compute om all property/atom omegax omegay omegaz",
        # angular momentum about the origin: orbital and the spheres' own, I = m d^2 / 10
        "variable lx atom mass*(y*vz-z*vy)+0.1*mass*c_om[1]",
        "variable ly atom mass*(z*vx-x*vz)+0.1*mass*c_om[2]",
        "variable lz atom mass*(x*vy-y*vx)+0.1*mass*c_om[3]",
        "compute L all reduce sum v_lx v_ly v_lz",
        "compute er all erotate/sphere",
        "variable e equal ke+c_er",
        "variable d12 equal sqrt((x[1]-x[2])^2+(y[1]-y[2])^2+(z[1]-z[2])^2)",
        "variable d24 equal sqrt((x[2]-x[4])^2+(y[2]-y[4])^2+(z[2]-z[4])^2)",
        "variable d34 equal sqrt((x[3]-x[4])^2+(y[3]-y[4])^2+(z[3]-z[4])^2)",
        "variable w1 equal c_om[1][1]",
        "thermo_style custom step ke v_e c_L[1] c_L[2] c_L[3] v_d12 v_d24 v_d34 v_w1 f_fc[3]",
        "thermo_modify format float %.15g norm no",
        "thermo %d" % (steps // 10),
        "run %d" % steps,
    ]) + "\n"


def acceleration(run):
    rows = {int(r["Step"]): r for r in run.thermo[-1]}
    v1, v2 = rows[T1_STEP]["c_s[2]"], rows[T2_STEP]["c_s[2]"]
    return (v2 - v1) / ((T2_STEP - T1_STEP) * DT), rows


def check_dumbbells(args, ck):
    t, g = math.radians(THETA), 1.0
    along, across = [(0, 0), (1, 0)], [(0, 0), (0, 1)]
    cases = [
        # tag, spheres, mu, np, expected acceleration (None: sticks)
        ("along_slides", along, 0.3, 1, g * (math.sin(t) - 0.3 * math.cos(t))),
        ("along_sticks", along, 0.7, 1, None),
        ("across_rolls", across, 0.3, 1, 5 / 7 * g * math.sin(t)),
        # the two spheres on two processes (the box splits at x = 0)
        ("along_slides_np2", [(-0.5, 0), (0.5, 0)], 0.3, 2, g * (math.sin(t) - 0.3 * math.cos(t))),
    ]
    serial = {}
    for tag, spheres, mu, np, expected in cases:
        run = e2e.run_lmp(args, dumbbell_deck(spheres, mu, "2 1 1" if np > 1 else None),
                          "clump_" + tag, np=np)
        if not ck.ran(run, "dumbbell %s (mu %g, np %d): run completes" % (tag, mu, np)):
            continue
        a, rows = acceleration(run)
        end = rows[T2_STEP]
        if expected is None:
            ck.check(abs(end["c_s[2]"]) < 1e-4 and abs(end["c_s[1]"] - 0.5) < 1e-3,
                     "%s: sticks (mu %g > tan %g)" % (tag, mu, THETA),
                     "v = %.3g, moved %.3g" % (end["c_s[2]"], end["c_s[1]"] - 0.5))
        else:
            err = e2e.rel_err(a, expected)
            ck.check(err < 1e-3, "%s: acceleration" % tag,
                     "a = %.8g, expected %.8g, rel err %.2g" % (a, expected, err))
        if tag.startswith("along"):
            w = max(abs(row["c_s[3]"]) for row in rows.values())
            ck.check(w < 1e-4, "%s: does not roll" % tag, "max |omega_y| = %.3g" % w)
        if tag == "across_rolls":
            err = e2e.rel_err(end["c_s[3]"] * 0.5, end["c_s[2]"])
            ck.check(err < 1e-3, "%s: rolls without slipping" % tag,
                     "omega_y r = %.8g, v = %.8g" % (end["c_s[3]"] * 0.5, end["c_s[2]"]))
        ck.check(all(row["f_fc[3]"] == 2 for row in rows.values() if row["Step"] > 0),
                 "%s: the floor's two contacts, none between the spheres" % tag,
                 "contacts %s" % sorted({row["f_fc[3]"] for row in rows.values()}))
        serial[tag] = a
    if "along_slides" in serial and "along_slides_np2" in serial:
        ck.agree(serial["along_slides_np2"], serial["along_slides"], 1e-6,
                 "a dumbbell split over two processes slides as in serial", "%.10g")


def check_tumbling(args, ck):
    steps = 2000
    runs = {}
    for np in (1, 2):
        run = e2e.run_lmp(args, tumbling_deck(steps, "2 1 1" if np > 1 else None),
                          "clump_tumbling_np%d" % np, np=np)
        if not ck.ran(run, "a tumbling L clump, np %d: run completes" % np):
            continue
        rows = run.thermo[-1]
        first, last = rows[0], rows[-1]
        L0 = [first["c_L[%d]" % k] for k in (1, 2, 3)]
        drift = max(abs(row["c_L[%d]" % k] - L0[k - 1]) for row in rows for k in (1, 2, 3))
        ck.check(drift < 1e-9 * math.sqrt(sum(x * x for x in L0)),
                 "np %d: angular momentum conserved" % np, "largest change %.3g" % drift)
        e_err = max(abs(row["v_e"] - first["v_e"]) for row in rows) / first["v_e"]
        ck.check(e_err < 1e-3, "np %d: energy conserved within 1e-3" % np, "%.3g" % e_err)
        shape = max(max(abs(row["v_d12"] - 1.0), abs(row["v_d24"] - math.sqrt(5.0)),
                        abs(row["v_d34"] - 1.0)) for row in rows)
        ck.check(shape < 1e-3, "np %d: the clump keeps its shape" % np, "%.3g" % shape)
        w1 = [row["v_w1"] for row in rows]
        ck.check(max(w1) - min(w1) > 0.05,
                 "np %d: an asymmetric top's angular velocity wanders" % np,
                 "omega_x from %.4g to %.4g" % (min(w1), max(w1)))
        ck.check(all(row["f_fc[3]"] == 0 for row in rows), "np %d: no contacts" % np)
        runs[np] = last
    if 1 in runs and 2 in runs:
        ck.agree(runs[2]["v_w1"], runs[1]["v_w1"], 1e-5,
                 "np 2 tumbles as serial (omega_x at the end)", "%.10g")
    if 1 in runs:
        check_restart(args, ck, runs[1])


def check_restart(args, ck, uninterrupted):
    first = tumbling_deck(1000).replace("run 1000", "run 1000\nwrite_restart clump.restart")
    run = e2e.run_lmp(args, first, "clump_restart_first")
    if not ck.ran(run, "tumbling, its first half and a restart file"):
        return
    lines = tumbling_deck(1000).splitlines()
    box = next(k for k, line in enumerate(lines) if line.startswith("region box"))
    start = next(k for k, line in enumerate(lines) if line.startswith("fix fc"))
    setup = [line for line in lines[:box] if "property/atom" not in line]
    material = [line for line in lines[box:start]
                if line.startswith(("pair_", "neighbor", "timestep"))]
    # fix property/atom comes again after read_restart, with its ID, to take its values back
    deck = "\n".join(setup + ["read_restart clump.restart",
                               "fix prop all property/atom mol ghost yes"] +
                      material + lines[start:]) + "\n"
    run = e2e.run_lmp(args, deck, "clump_restart_second")
    if not ck.ran(run, "tumbling, its second half from the restart file"):
        return
    last = run.thermo[-1][-1]
    ck.agree(last["c_L[3]"], uninterrupted["c_L[3]"], 1e-9,
             "after the restart: the angular momentum kept", "%.12g")
    ck.agree(last["v_e"], uninterrupted["v_e"], 1e-3,
             "after the restart: the energy of the uninterrupted run", "%.8g")


def drop_deck(processors=None, apart=False):
    """apart: the clump on one process (x > 0) and a lone sphere, a clump of one, dropped on
    the other's side: a process whose contacts hold no joint beside one whose do."""
    spheres = [(0, 0, 3), (0.8, 0.3, 3.5), (-0.7, 0.5, 3.4)]
    if apart:
        spheres = [(x + 5.0, y, z) for x, y, z in spheres] + [(-5.0, 0.0, 2.0)]
    lines = clump_opening("-10 10 -10 10 -1 20", spheres,
                          3.0, processors=processors, law="granular",
                          coeff="hertz/material 1e5 0.3 0.3 tangential mindlin NULL 1.0 0.5 "
                          "damping tsuji", dt=0.001)
    if apart:
        lines.append("set atom 4 mol 2")
    return "\n".join(lines + [
        "velocity all set 0.5 0 0",
        "fix g all gravity 9.81 vector 0 0 -1",
        "fix fc all fibre_contact wall zplane 0.0 NULL clumps molecule",
        "compute er all erotate/sphere",
        "variable pe atom mass*9.81*z",
        "compute pe all reduce sum v_pe",
        "variable total equal ke+c_er+c_pe+f_fc[18]",
        "thermo_style custom step ke c_er v_total f_fc[18]",
        "thermo_modify format float %.15g norm no",
        "thermo 100",
        "run 3000",
    ]) + "\n"


def check_drop(args, ck):
    for np, apart in ((1, False), (2, False), (2, True)):
        name = "a clump dropped onto a floor, np %d%s" % (np, ", a lone sphere apart" * apart)
        run = e2e.run_lmp(args, drop_deck("2 1 1" if np > 1 else None, apart),
                          "clump_drop_np%d%s" % (np, "_apart" * apart), np=np)
        if not ck.ran(run, name + ": run completes"):
            continue
        rows = run.thermo[-1]
        e0 = rows[0]["v_total"]
        err = max(abs(row["v_total"] - e0) for row in rows) / e0
        ck.check(err < 2e-3, "np %d: energy, potential and dissipation add up" % np,
                 "largest imbalance %.3g of %.5g; dissipated %.4g" % (err, e0,
                                                                       rows[-1]["f_fc[18]"]))
        ck.check(rows[-1]["f_fc[18]"] > 0.5 * e0, "np %d: the impacts dissipate" % np,
                 "%.4g of %.4g" % (rows[-1]["f_fc[18]"], e0))


def check_heap(args, ck):
    deck = os.path.join(args.source, "examples", "clumps", "in.clumps")
    figures = {}
    for mode, dt, steps in (("native", 0.001, 40000), ("fibre", 0.025, 1600)):
        run = e2e.run_lmp(args, open(deck).read(), "clump_heap_" + mode, variables={
            "mode": mode, "dt": dt, "steps": steps, "ywidth": YWIDTH, "seed": 4767548})
        if not ck.ran(run, "the clump heap, %s: run completes" % mode):
            return
        ck.check(run.last("Atoms") == 5 * CLUMPS, "%s: no atom lost" % mode,
                 "%d" % run.last("Atoms"))
        with open(os.path.join(args.workdir, "dump.clumps.%s.4767548" % mode)) as f:
            lines = f.read().splitlines()
        start = next(k for k, line in enumerate(lines) if line.startswith("ITEM: ATOMS")) + 1
        figures[mode] = heap_figures([[float(t) for t in line.split()] for line in lines[start:]],
                                     YWIDTH)
    if len(figures) == 2:
        ck.agree(figures["fibre"][0], figures["native"][0], 0.10,
                 "the heap's height within 10% of native's", "%.3f")
        ck.agree(figures["fibre"][1], figures["native"][1], 0.10,
                 "the heap's spread within 10% of native's", "%.3f")
        diff = figures["fibre"][2] - figures["native"][2]
        ck.check(abs(diff) < 6.0, "the heap's angle of repose within 6 degrees of native's",
                 "%.1f against %.1f" % (figures["fibre"][2], figures["native"][2]))


def heap_figures(atoms, ywidth):
    """Height (99th percentile of the tops), spread (standard deviation of x) and angle of
    repose (the flanks' fitted slope) of a heap from dump rows id mol x y z radius, as
    examples/clumps/clumps.py measures them: per unit bin of x the mean over 4-wide bins of y
    of the highest top, fitted against the distance from the centre where it lies between 15%
    and 85% of the height."""
    x = [a[2] for a in atoms]
    top = sorted(a[4] + a[5] for a in atoms)
    at = 0.99 * (len(top) - 1)  # numpy's percentile: linear between the two nearest
    height = top[int(at)] + (at - int(at)) * (top[min(int(at) + 1, len(top) - 1)] - top[int(at)])
    xc = sum(x) / len(x)
    spread = math.sqrt(sum((v - xc) ** 2 for v in x) / len(x))
    highest = {}
    for a in atoms:
        if 0.0 <= a[3] < ywidth:  # an atom just outside the periodic box is in no bin
            key = (int(math.floor(a[2])), int(math.floor(a[3] / 4.0)))
            highest[key] = max(highest.get(key, -math.inf), a[4] + a[5])
    d, h = [], []
    for lo in range(60):
        tops = [t for (i, _), t in highest.items() if i == lo]
        if tops and 0.15 * height < sum(tops) / len(tops) < 0.85 * height:
            d.append(abs(lo + 0.5 - xc))
            h.append(sum(tops) / len(tops))
    dm, hm = sum(d) / len(d), sum(h) / len(h)
    slope = (sum((a - dm) * (b - hm) for a, b in zip(d, h)) /
             sum((a - dm) ** 2 for a in d))
    return height, spread, math.degrees(math.atan(-slope))


def check_errors(args, ck):
    plain = dumbbell_deck([(0, 0), (1, 0)], 0.3).replace(
        "fix prop all property/atom mol ghost yes\n", "").replace("set atom * mol 1\n", "")
    run = e2e.run_lmp(args, plain, "clump_no_molecules")
    ck.check(run.rc != 0 and "clumps molecule requires molecule IDs" in run.output,
             "clumps without molecule IDs: an error that says what to add", run.error_line())
    bad = dumbbell_deck([(0, 0), (1, 0)], 0.3).replace("clumps molecule", "clumps rigid")
    run = e2e.run_lmp(args, bad, "clump_bad_value")
    ck.check(run.rc != 0 and "expected 'clumps molecule|none', got 'rigid'" in run.output,
             "clumps with a bad value: the expected form", run.error_line())


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("clumps: rigid bodies of spheres")
    check_dumbbells(args, ck)
    check_tumbling(args, ck)
    check_drop(args, ck)
    check_heap(args, ck)
    check_errors(args, ck)
    ck.close()


if __name__ == "__main__":
    main()
