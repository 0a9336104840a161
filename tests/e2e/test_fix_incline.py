"""Acceptance 2: a sphere on an incline (tilted gravity, zplane floor).

A sphere of diameter 1 rests on a zplane wall; gravity g = 1 is tilted by theta about y.
The acceleration is measured from the velocity along the slope between t = 2 and t = 10
(dt = 0.01). Expected, with mu = Coulomb friction and mu_r = rolling resistance:
- rolling locked (mu_r large): sticks for tan(theta) < mu, slides with
  a = g (sin(theta) - mu cos(theta)) above;
- rolling free (mu_r = 0): rolls without slipping with a = 5/7 g sin(theta) while
  tan(theta) < 7/2 mu, slides with a = g (sin(theta) - mu cos(theta)) above;
- rolling resistance mu_r: stops for tan(theta) < mu_r, else rolls with
  a = 5/7 g (sin(theta) - mu_r cos(theta));
- twisting resistance: a sphere spinning about the normal stops at the rate
  mu_t r N / I = mu_t g / (0.4 r), and stays stopped;
- a sphere launched at v0 along a flat floor slides, spins up and rolls on at 5/7 v0; with
  rolling locked it slides to a stop at x = v0^2 / (2 mu g) without spinning;
- a sphere rolling at v0 on the decks' material (pair granular, rolling sds 1e3 10 0.3, whose
  damper outlasts the step) stops at x = v0^2 / (2 a), a = 5/7 mu_r g, as LAMMPS's own run does.
Accelerations must agree within 2%; a sticking sphere must not move by more than 1e-3
diameters (SPOOK's velocity-level friction allows a creep of eps_t F_t / (d dt) per unit time,
a few 1e-6 here).
"""

import math

import fibre_e2e as e2e

DT = 0.01
T1_STEP, T2_STEP = 200, 1000


def deck(theta_deg, opts, omega_z=0.0, vx=0.0):
    t = math.radians(theta_deg)
    return "\n".join([
        "atom_style sphere",
        "atom_modify map array",
        "boundary p p f",
        "newton off",
        "comm_modify vel yes",
        "region box block -10 10 -3 3 0 5 units box",
        "create_box 1 box",
        "create_atoms 1 single 0 0 0.5 units box",
        "set atom 1 diameter 1.0 density 1.0",
        "velocity all set %.17g 0 0" % vx,
        "set atom 1 omega 0 0 %.17g" % omega_z,
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0",
        "pair_coeff * *",
        "neighbor 0.2 bin",
        "timestep %g" % DT,
        "fix g all gravity 1.0 vector %.17g 0 %.17g" % (math.sin(t), -math.cos(t)),
        "fix fc all fibre_contact wall zplane 0.0 NULL " + opts,
        # one atom: the sums are its values
        "compute p all property/atom xu z vx omegay omegaz",
        "compute s all reduce sum c_p[1] c_p[2] c_p[3] c_p[4] c_p[5]",
        "thermo_style custom step c_s[1] c_s[2] c_s[3] c_s[4] c_s[5] f_fc[3] f_fc[10]",
        "thermo_modify format float %.15g",
        "thermo 100",
        "run %d" % T2_STEP,
    ]) + "\n"


def sds_deck(v0, dt):
    """A sphere of diameter 0.8 rolling at v0 along the floor, the material decks' pair_coeff."""
    law = ("hertz/material 1e8 0.1 0.2857142857 tangential mindlin NULL 1.0 0.5 "
           "rolling sds 1e3 10 0.3 damping tsuji")
    return "\n".join(e2e.sphere_box("-5 20 -3 3 -1 5") + [
        "create_atoms 1 single 0 0 0.4 units box",
        "set atom 1 diameter 0.8 density 1.0",
        "velocity all set %.17g 0 0 units box" % v0,
        "set atom 1 omega 0 %.17g 0" % (v0 / 0.4),
        "pair_style granular",
        "pair_coeff * * " + law,
        "neighbor 0.2 bin",
        "timestep %g" % dt,
        "fix g all gravity 9.81 vector 0 0 -1",
        "fix fc all fibre_contact wall zplane 0.0 NULL",
        "compute p all property/atom xu vx",
        "compute s all reduce sum c_p[1] c_p[2]",
        "thermo_style custom step c_s[1] c_s[2]",
        "thermo_modify format float %.15g",
        "thermo 100",
        "run %d" % round(2.0 / dt),
    ]) + "\n"


def acceleration(run):
    rows = {int(r["Step"]): r for r in run.thermo[-1]}
    v1, v2 = rows[T1_STEP]["c_s[3]"], rows[T2_STEP]["c_s[3]"]
    return (v2 - v1) / ((T2_STEP - T1_STEP) * DT), rows


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("sphere on an incline")
    g, mu, r = 1.0, 0.5, 0.5
    cases = [
        # tag, theta, options, expected acceleration (None: sticks)
        ("locked_stick", 20.0, "mu 0.5 mu_roll 10", None),
        ("locked_stick_near", 25.0, "mu 0.5 mu_roll 10", None),
        ("locked_slide", 35.0, "mu 0.5 mu_roll 10",
         g * (math.sin(math.radians(35)) - mu * math.cos(math.radians(35)))),
        ("free_roll", 20.0, "mu 0.5 mu_roll 0", 5 / 7 * g * math.sin(math.radians(20))),
        ("free_roll_rows3", 20.0, "mu 0.5 rows 3", 5 / 7 * g * math.sin(math.radians(20))),
        ("free_slide", 70.0, "mu 0.5 mu_roll 0",
         g * (math.sin(math.radians(70)) - mu * math.cos(math.radians(70)))),
        ("resisted_roll", 20.0, "mu 0.5 mu_roll 0.1",
         5 / 7 * g * (math.sin(math.radians(20)) - 0.1 * math.cos(math.radians(20)))),
        ("resisted_stop", 4.0, "mu 0.5 mu_roll 0.1", None),
        ("direct_slide", 35.0, "mu 0.5 mu_roll 10 solver direct",
         g * (math.sin(math.radians(35)) - mu * math.cos(math.radians(35)))),
        ("body_roll", 20.0, "mu 0.5 mu_roll 0.1 form body",
         5 / 7 * g * (math.sin(math.radians(20)) - 0.1 * math.cos(math.radians(20)))),
    ]
    for tag, theta, opts, expected in cases:
        run = e2e.run_lmp(args, deck(theta, opts), "incline_" + tag)
        if not ck.ran(run, "%s (theta %g, %s): run completes" % (tag, theta, opts)):
            continue
        a, rows = acceleration(run)
        x_end = rows[T2_STEP]["c_s[1]"]
        if expected is None:
            ck.check(abs(x_end) < 1e-3 and abs(rows[T2_STEP]["c_s[3]"]) < 1e-4,
                     "%s: sticks (tan %g < bound)" % (tag, math.tan(math.radians(theta))),
                     "moved %.3g in %g time units, v = %.3g"
                     % (x_end, T2_STEP * DT, rows[T2_STEP]["c_s[3]"]))
        else:
            err = e2e.rel_err(a, expected)
            ck.check(err < 0.02, "%s: acceleration" % tag,
                     "a = %.6g, expected %.6g, rel err %.2g%%" % (a, expected, 100 * err))
        if "locked" in tag:
            w = max(abs(row["c_s[4]"]) for row in rows.values())
            ck.check(w < 1e-4, "%s: rolling locked, no spin" % tag,
                     "max |omega_y| = %.3g, bound 1e-4 (creep)" % w)
        if tag.startswith("free_roll") or tag in ("resisted_roll", "body_roll"):
            v, w = rows[T2_STEP]["c_s[3]"], rows[T2_STEP]["c_s[4]"]
            err = e2e.rel_err(w * r, v)
            ck.check(err < 0.02, "%s: rolls without slipping (omega_y r = v)" % tag,
                     "omega_y r = %.6g, v = %.6g" % (w * r, v))
        z = rows[T2_STEP]["c_s[2]"]
        ck.check(abs(z - 0.5) < 1e-5, "%s: stays on the floor" % tag, "z = %.10g" % z)

    # a sphere launched along a flat floor: slides, spins up and rolls on at 5/7 v0
    # (no rolling resistance), or slides to a stop at t = v0 / (mu g) without spinning
    v0 = 1.0
    for tag, opts in [("launch_roll", "mu 0.5"), ("launch_roll_rows3", "mu 0.5 rows 3"),
                      ("launch_locked", "mu 0.5 mu_roll 10")]:
        run = e2e.run_lmp(args, deck(0.0, opts, vx=v0), "incline_" + tag)
        if not ck.ran(run, "%s: run completes" % tag):
            continue
        rows = {int(row["Step"]): row for row in run.thermo[-1]}
        v_end, w_end = rows[T2_STEP]["c_s[3]"], rows[T2_STEP]["c_s[4]"]
        if "locked" in tag:
            stop = v0 / (mu * g)
            x_stop = v0 * stop / 2
            ck.check(abs(v_end) < 1e-6 and abs(rows[T2_STEP]["c_s[1]"] - x_stop) < 0.01,
                     "%s: slides to a stop at x = v0^2 / (2 mu g)" % tag,
                     "v = %.3g, x = %.6g, expected %.6g" % (v_end, rows[T2_STEP]["c_s[1]"],
                                                           x_stop))
            w = max(abs(row["c_s[4]"]) for row in rows.values())
            ck.check(w < 1e-4, "%s: rolling locked, no spin" % tag,
                     "max |omega_y| = %.3g, bound 1e-4 (creep)" % w)
        else:
            ck.check(e2e.rel_err(v_end, 5 / 7 * v0) < 1e-3 and
                     e2e.rel_err(w_end * r, v_end) < 1e-3,
                     "%s: rolls on at 5/7 v0 without slipping" % tag,
                     "v = %.6g (5/7 v0 = %.6g), omega_y r = %.6g" % (v_end, 5 / 7 * v0,
                                                                    w_end * r))

    # SDS rolling resistance at the decks' step (4.4 ms; the spring's damper lasts 10 ms): a
    # sphere rolling at 3 m/s stops at v0^2 / (2 a), a = 5/7 mu_r g (2.14 m)
    v0, mu_r = 3.0, 0.3
    run = e2e.run_lmp(args, sds_deck(v0, 4.4e-3), "incline_sds_roll")
    if ck.ran(run, "sds_roll: run completes"):
        last = run.thermo[-1][-1]
        x_stop = v0 * v0 / (2.0 * 5.0 / 7.0 * mu_r * 9.81)
        ck.check(abs(last["c_s[2]"]) < 1e-3 and e2e.rel_err(last["c_s[1]"], x_stop) < 0.02,
                 "sds_roll: stops at v0^2 / (2 * 5/7 mu_r g)",
                 "x = %.4g, expected %.4g, v = %.3g" % (last["c_s[1]"], x_stop, last["c_s[2]"]))

    # twisting resistance: spin about the normal decays at mu_t g / (0.4 r)
    mu_t, w0 = 0.2, 2.0
    run = e2e.run_lmp(args, deck(0.0, "mu 0.5 mu_twist %g" % mu_t, omega_z=w0), "incline_twist")
    if ck.ran(run, "twist: run completes"):
        rows = {int(r["Step"]): r for r in run.thermo[-1]}
        # The spin stops at t = w0 / rate (2 s, step 200): measure before that.
        rate = (rows[0]["c_s[5]"] - rows[100]["c_s[5]"]) / (100 * DT)
        expected = mu_t * g / (0.4 * r)
        err = e2e.rel_err(rate, expected)
        ck.check(err < 0.02, "twist: spin decays at mu_t g / (0.4 r)",
                 "rate %.6g, expected %.6g, rel err %.2g%%" % (rate, expected, 100 * err))
        ck.check(abs(rows[T2_STEP]["c_s[5]"]) < 1e-6, "twist: spin stops and stays stopped",
                 "omega_z = %.3g at t = %g" % (rows[T2_STEP]["c_s[5]"], T2_STEP * DT))
    ck.close()


if __name__ == "__main__":
    main()
