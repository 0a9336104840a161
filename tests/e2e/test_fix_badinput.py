"""Acceptance 7: bad input gives a clear LAMMPS error and a non-zero exit status.

Every keyword with a missing or invalid value, an unknown keyword, a wrong atom style, no
pair style, a pair style without a usable neighbor list, an unknown or moving region, pair
forces switched back on, a 2d box, and an infinite force or velocity (an error naming the atom
and the step). Each case checks the exit status and that the ERROR
line names the problem (the keyword and the expected form). Two runs that complete check
the log messages: another fix integrating the same atoms (a warning), and the pair style's
forces switched off.
"""

import fibre_e2e as e2e

BASE = """atom_style {style}
boundary f f f
newton off
comm_modify vel yes
region box block -3 3 -3 3 0 6 units box
create_box 1 box
create_atoms 1 single 0 0 0.5 units box
{set}
{pair}
neighbor 0.2 bin
timestep 0.01
{pre}
fix fc all fibre_contact {args}
{post}
run 2
"""

GRAN = "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0\npair_coeff * *"

TWO_D = """atom_style sphere
dimension 2
boundary f f p
region box block -3 3 -3 3 -0.5 0.5 units box
create_box 1 box
create_atoms 1 single 0 0 0 units box
""" + GRAN + """
fix fc all fibre_contact
run 2
"""

# (name, fix arguments, expected text in the ERROR line, deck overrides)
CASES = [
    ("form_invalid", "form primal", "expected 'form body|contact', got 'primal'", {}),
    ("form_missing", "form", "expected 'form body|contact'", {}),
    # the choices are Method's name table: cg (uzawa an accepted alias), cr, minres, direct, pgs
    ("solver_invalid", "solver bicgstab", "expected 'solver cg|cr|minres|direct|pgs|nncg|fbgs|apgd', got "
     "'bicgstab'", {}),
    ("precond_invalid", "precond ilu", "expected 'precond none|jacobi|block|fibre|tree', got "
     "'ilu'", {}),
    ("weight_invalid", "weight mass", "expected 'weight z|straight|impulse', got 'mass'", {}),
    ("tol_negative", "tol -1e-6", "expected 'tol none|<positive number>', got '-1e-6'", {}),
    ("tol_text", "tol small", "expected 'tol none|<positive number>', got 'small'", {}),
    ("tol_missing", "mu 0.3 tol", "expected 'tol none|<positive number>'", {}),
    ("linear_tol_zero", "linear_tol 0", "expected 'linear_tol <positive number>', got '0'", {}),
    ("pass_tol_zero", "pass_tol 0", "expected 'pass_tol <positive number>'", {}),
    ("pass_tol_missing", "pass_tol", "expected 'pass_tol <positive number>'", {}),
    ("sweeps_negative", "sweeps -1", "expected 'sweeps <non-negative integer>', got '-1'", {}),
    ("sweeps_real", "sweeps 2.5", "expected 'sweeps <non-negative integer>', got '2.5'", {}),
    ("min_sweeps_negative", "min_sweeps -3",
     "expected 'min_sweeps <non-negative integer>', got '-3'", {}),
    ("sweep_tol_zero", "sweep_tol 0", "expected 'sweep_tol <positive number>', got '0'", {}),
    ("sweep_tol_missing", "sweep_tol", "expected 'sweep_tol <positive number>'", {}),
    ("sweep_blocks_word", "sweep_blocks maybe", "expected 'sweep_blocks yes|no', got 'maybe'", {}),
    ("sweep_groups_word", "sweep_groups 1", "expected 'sweep_groups yes|no', got '1'", {}),
    ("sweep_groups_missing", "sweep_groups", "expected 'sweep_groups yes|no'", {}),
    ("maxiter_zero", "maxiter 0", "expected 'maxiter <positive integer>', got '0'", {}),
    ("maxiter_real", "maxiter 2.5", "expected 'maxiter <positive integer>', got '2.5'", {}),
    ("compliance_one", "compliance 1e-6",
     "expected 'compliance auto|material' or 'compliance <eps_n> <eps_t>'", {}),
    ("compliance_negative", "compliance -1 1e-6", "'compliance <eps_n> <eps_t>' (positive "
     "numbers), got '-1'", {}),
    ("damping_zero", "damping 0", "expected 'damping <positive number of steps>', got '0'", {}),
    ("mu_negative", "mu -0.1", "expected 'mu <non-negative number>', got '-0.1'", {}),
    ("mu_roll_text", "mu_roll rough", "expected 'mu_roll <non-negative number>', got 'rough'",
     {}),
    ("mu_twist_missing", "mu_twist", "expected 'mu_twist <non-negative number>'", {}),
    ("rows_invalid", "rows 4", "expected 'rows 3|6|auto', got '4'", {}),
    ("active_set_zero", "active_set 0", "expected 'active_set <positive integer>', got '0'",
     {}),
    ("wall_kind", "wall cylinder 1 2", "'wall xplane|yplane|zplane <lo|NULL> <hi|NULL>', "
     "'wall xcylinder|ycylinder|zcylinder <radius> [<c1> <c2>]', 'wall region <region-ID>' or "
     "'wall mesh <fix-ID>' (optionally 'type <T>' or fix wall/gran's interaction after 'wall'), "
     "got 'cylinder'", {}),
    ("wall_cylinder_radius", "wall zcylinder -1", "expected 'wall zcylinder <radius> [<c1> <c2>]' "
     "(radius > 0), got '-1'", {}),
    ("wall_type_range", "wall type 9 zplane 0 NULL", "'wall type 9 zplane ...': type 9 is not an "
     "atom type (1 to 1)", {}),
    ("wall_interaction", "wall granular hertz/material 1e5 0.3 zplane 0 NULL",
     "cannot read 'hertz/material' and its arguments as fix wall/gran granular's", {}),
    ("wall_interaction_null", "wall granular hertz 1e5 0.3 tangential mindlin NULL 1.0 0.5 zplane "
     "0 NULL", "'tangential mindlin NULL' needs hertz/material, dmt or jkr before it", {}),
    ("wall_interaction_gran", "wall hooke 1e5 NULL zplane 0 NULL", "expected 'hooke <kn> <kt|NULL> "
     "<gamman> <gammat|NULL> <xmu> <dampflag>'", {}),
    ("wall_mesh_lammps", "wall mesh cad", "mesh walls (fix mesh/surface) need the LIGGGHTS front "
     "end", {}),
    ("wall_plane_missing", "wall zplane 0.0", "expected 'wall zplane <lo|NULL> <hi|NULL>'",
     {}),
    ("wall_plane_null", "wall zplane NULL NULL", "expected 'wall zplane <lo|NULL> <hi|NULL>' "
     "with at least one of lo and hi a number", {}),
    ("wall_plane_order", "wall xplane 2 -2", "expected 'wall xplane <lo|NULL> <hi|NULL>' with "
     "lo < hi, got '2 -2'", {}),
    ("wall_plane_text", "wall yplane low 2", "expected 'wall yplane <lo|NULL> <hi|NULL>', got "
     "'low'", {}),
    ("wall_region_missing", "wall region", "expected 'wall region <region-ID>'", {}),
    ("wall_region_unknown", "wall region nowhere", "Region ID 'nowhere' for fix fibre_contact "
     "'wall region' does not exist", {}),
    ("export_zero", "export 0 sys", "expected 'export <N> <file-prefix>'", {}),
    ("export_missing_prefix", "export 10", "expected 'export <N> <file-prefix>'", {}),
    ("unknown_keyword", "mu 0.3 stiffness 1e5", "got 'stiffness'", {}),
    ("rows3_rolling", "rows 3 mu_roll 0.1", "mu_roll and mu_twist need 'rows 6'", {}),
    ("atom_style", "", "requires atom attributes radius, rmass, omega and torque",
     {"style": "atomic", "set": "mass 1 1.0"}),
    ("no_pair_style", "", "requires a granular pair style for its neighbor list",
     {"pair": ""}),
    ("pair_not_granular", "", "requires a granular pair style (gran/hooke",
     {"pair": "pair_style lj/cut 2.5\npair_coeff * * 1.0 1.0"}),
    ("pair_after_fix", "", "define the pair style before fix fibre_contact",
     {"pair": "", "post": GRAN}),
    ("pair_compute_yes", "", "pair style's force computation is on",
     {"post": "pair_modify compute yes"}),
    ("moving_union_side_out", "wall region cup", "a moving union inside a region with 'side "
     "out' is not supported", {"pre": "variable vz equal 0.1*time\n"
                              "region c1 cylinder z 0 0 2.5 0 5 side in move NULL NULL v_vz "
                              "units box\n"
                              "region c2 sphere 0 0 0 1 side in units box\n"
                              "region inner union 2 c1 c2\n"
                              "region c3 sphere 0 0 8 1 side in units box\n"
                              "region cup union 2 inner c3 side out"}),
    ("varshape_region", "wall region ball", "a region whose shape changes over time",
     {"pre": "variable rad equal 2.0+0.1*time\nregion ball sphere 0 0 2 v_rad side in units box"}),
    ("two_d", "", "requires a 3d simulation", {"deck": TWO_D}),
    ("infinite_force", "", "non-finite force of atom 1 at step 1",
     {"pre": "fix push all addforce 0 0 1e400"}),
    ("infinite_velocity", "", "non-finite velocity of atom 1 at step 1",
     {"pre": "velocity all set 0 0 1e400 units box"}),
    ("restitution", "restitution 1.5", "expected 'restitution <number in [0, 1]>', got '1.5'",
     {}),
    ("bounce_speed", "restitution 0.5 bounce_speed fast",
     "expected 'bounce_speed auto|<non-negative speed>', got 'fast'", {}),
    ("normal_relaxation_invalid", "normal_relaxation euler",
     "expected 'normal_relaxation law|spook', got 'euler'", {}),
    ("normal_relaxation_missing", "normal_relaxation", "expected 'normal_relaxation law|spook'",
     {}),
]


# (name, fix arguments, expected text in a WARNING line, deck overrides): runs that complete
WARN_CASES = [
    ("double_integration", "", "Fix fibre_contact: fix nve (nve/sphere) also time-integrates 1 "
     "atoms of group all", {"pre": "fix nve all nve/sphere"}),
    ("pair_switched_off", "", "switched off the force computation of pair style gran/hooke",
     {}),
    ("pair_local", "", "compute pl (pair/local) reads the pair style, whose forces are switched "
     "off", {"post": "compute pl all pair/local dist"}),
    ("short_damping", "damping 0.5", "Fix fibre_contact: damping 0.5 is below 2 steps", {}),
    ("wall_gran_kept", "wall zplane 0 NULL", "fix w (wall/gran) computes wall forces of its own",
     {"post": "fix w all wall/gran hooke 2000 NULL 50 NULL 0.5 0 zplane 0 NULL"}),
    ("rotation_axis", "wall region cup", "region cup rotates about an axis of length 1.41421",
     {"pre": "variable th equal 0.1*time\nregion cup block -2 2 -2 2 0 5 side in units box "
             "rotate v_th 0 0 0 1 1 0"}),
]


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("bad input: %d cases" % len(CASES))
    for name, fix_args, expected, over in CASES:
        fields = {"style": "sphere", "set":
                  "set atom 1 diameter 1.0 density 1.0", "pair": GRAN, "pre": "", "post": "",
                  "args": fix_args}
        fields.update(over)
        deck = fields["deck"] if "deck" in fields else BASE.format(**fields)
        run = e2e.run_lmp(args, deck, "bad_" + name, timeout=120)
        err = run.error_line()
        ck.check(run.rc != 0 and expected in err and "ERROR" in err,
                 "%s: '%s' fails" % (name, fix_args) if fix_args else "%s fails" % name,
                 "rc %d, %s" % (run.rc, err if err else "no ERROR line"))
    for name, fix_args, expected, over in WARN_CASES:
        fields = {"style": "sphere", "set": "set atom 1 diameter 1.0 density 1.0",
                  "pair": GRAN, "pre": "", "post": "", "args": fix_args}
        fields.update(over)
        run = e2e.run_lmp(args, BASE.format(**fields), "warn_" + name, timeout=120)
        lines = [line.strip() for line in run.output.splitlines() if expected in line]
        ck.check(run.rc == 0 and bool(lines), "%s: runs and says so" % name,
                 "rc %d, %s" % (run.rc, lines[0] if lines else "message missing"))
    ck.close()


if __name__ == "__main__":
    main()
