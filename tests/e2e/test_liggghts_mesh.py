"""The LIGGGHTS front end (liggghts_fibre): mesh walls, materials from fix property/global,
MPI, restart and bad input, against analytic references.

- Rest on a mesh floor: with `compliance material` a sphere's overlap under its weight is
  Hertz's d = (3 m g / (4 Y* sqrt(r)))^(2/3), Y* from youngsModulus and poissonsRatio of the
  sphere's type and the mesh's type (within 1%), with the default (the material's
  compliance) and typed alike; rigid rows (`compliance auto`) keep it below 1e-4 r.
- The normal dashpot from coefficientRestitution e is LIGGGHTS's hertz one, also at e = 1.
- LIGGGHTS's hooke with a characteristicVelocity v_c: a sphere at rest on a mesh floor
  overlaps by m g / k_n, k_n = 16/15 sqrt(r) Y* (15 m v_c^2 / (16 sqrt(r) Y*))^(1/5), as
  native LIGGGHTS's (both within 1%).
- An inclined mesh plane: a sphere rolls without slipping at a = 5/7 g sin(theta) when
  tan(theta) < 7/2 mu, and slides at a = g (sin(theta) - mu cos(theta)) above (within 2%); mu
  is the coefficientFriction of the pair (sphere type, mesh type).
- A conveyor: a sphere at rest on a mesh moved by fix move/mesh at U is carried to 2/7 U
  (angular momentum about the contact point; within 2%): the mesh's node velocities enter the
  contacts.
- Faces, edges and vertices: spheres dropped on a closed cube mesh (12 triangles) from above
  its face, edges and corner never enter it with rigid rows (centre distance >= 0.999 r at
  every dump) and come to rest.
- mpirun -np 2: a pile of spheres settling in a mesh box gives the serial run's centre of mass
  (1e-9 m) and kinetic energy to the solver tolerance (250 steps: later the lattice's columns
  buckle, and any difference grows).
- Restart: a run continued from write_restart (mesh and fix defined again) ends where the
  uninterrupted run ends.
- Bad input: a missing or non-mesh wall fix, a LAMMPS-style region wall, a missing
  coefficientFriction and a wrongly shaped table are LIGGGHTS errors that name them.
"""

import math

import fibre_e2e as e2e

# LIGGGHTS's thermo header drops the v_, c_ and f_ prefixes: v_z is "z", f_fc[3] "fc[3]".

R = 0.005       # sphere radius (m)
RHO = 2500.0
G = 9.81
E_SPHERE, E_MESH, NU = 5e6, 2e7, 0.3


def mass():
    return RHO * 4.0 / 3.0 * math.pi * R ** 3


def y_eff():
    return 1.0 / ((1 - NU ** 2) / E_SPHERE + (1 - NU ** 2) / E_MESH)


def stl(path, triangles):
    with open(path, "w") as f:
        f.write("solid m\n")
        for tri in triangles:
            f.write(" facet normal 0 0 0\n  outer loop\n")
            for p in tri:
                f.write("   vertex %.17g %.17g %.17g\n" % p)
            f.write("  endloop\n endfacet\n")
        f.write("endsolid m\n")


def square(half, z=0.0, angle=0.0, half_y=None):
    """Two triangles of a rectangle of half-widths `half` (x) and `half_y` (y, default `half`),
    tilted by `angle` about y."""
    c, s = math.cos(angle), math.sin(angle)

    def p(x, y):
        return (x * c, y, z - x * s)
    hy = half if half_y is None else half_y
    a, b, cc, d = p(-half, -hy), p(half, -hy), p(half, hy), p(-half, hy)
    return [(a, b, cc), (a, cc, d)]


def cube(lo, hi):
    """A closed cube mesh, 12 triangles."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
         (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    quads = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (2, 3, 7, 6), (1, 2, 6, 5), (3, 0, 4, 7)]
    tris = []
    for a, b, c, d in quads:
        tris += [(v[a], v[b], v[c]), (v[a], v[c], v[d])]
    return tris


def header(box, mu=0.5, extra_material=(), restitution=0.3, boundary="f f f", processors=None):
    lines = ["atom_style granular", "atom_modify map array", "boundary " + boundary,
             "newton off", "communicate single vel yes", "units si"]
    if processors:
        lines.append("processors " + processors)
    lines += ["region box block %s units box" % box, "create_box 2 box",
              "neighbor 0.002 bin", "neigh_modify delay 0",
              "fix m1 all property/global youngsModulus peratomtype %g %g" % (E_SPHERE, E_MESH),
              "fix m2 all property/global poissonsRatio peratomtype %g %g" % (NU, NU),
              "fix m3 all property/global coefficientRestitution peratomtypepair 2 "
              "%g %g %g %g" % ((restitution,) * 4),
              "fix m4 all property/global coefficientFriction peratomtypepair 2 "
              "%g %g %g %g" % ((mu,) * 4)]
    lines += list(extra_material)
    lines += ["pair_style gran model hertz tangential history", "pair_coeff * *"]
    return lines


def one_sphere(x, y, z):
    return ["create_atoms 1 single %.17g %.17g %.17g units box" % (x, y, z),
            "set atom 1 diameter %g density %g" % (2 * R, RHO)]


def hooke_rest(args, checks):
    """LIGGGHTS's hooke (characteristicVelocity v_c): a sphere at rest on a mesh floor overlaps
    by m g / k_n, k_n = 16/15 sqrt(r) Y* (15 m v_c^2 / (16 sqrt(r) Y*))^(1/5) of the sphere
    against the wall, as native LIGGGHTS's fix wall/gran does (both within 1%)."""
    v_c = 2.0
    k_n = 16.0 / 15.0 * math.sqrt(R) * y_eff() * (
        15.0 * mass() * v_c ** 2 / (16.0 * math.sqrt(R) * y_eff())) ** 0.2
    expected = mass() * G / k_n
    overlaps = {}
    for method in ("fibre", "native"):
        walls = ("fix fc all fibre_contact wall mesh floor" if method == "fibre" else
                 "fix n all nve/sphere\nfix w all wall/gran model hooke tangential history mesh "
                 "n_meshes 1 meshes floor")
        deck = header("-0.05 0.05 -0.05 0.05 -0.01 0.05") + one_sphere(0, 0, R) + [
            "fix m5 all property/global characteristicVelocity scalar %g" % v_c,
            "timestep 0.0001", "fix g all gravity 9.81 vector 0 0 -1",
            "fix floor all mesh/surface file floor.stl type 2", walls,
            "variable z equal z[1]", "thermo_style custom step v_z",
            "thermo_modify format float %.15g", "thermo 1000", "run 20000"]
        deck = [line.replace("model hertz", "model hooke") for line in deck]
        run = e2e.run_lmp(args, "\n".join(deck) + "\n", "hooke_rest_" + method)
        if checks.ran(run):
            overlaps[method] = R - run.last("z")
            checks.agree(overlaps[method], expected, 0.01,
                         "hooke, %s: the overlap at rest is m g / k_n of LIGGGHTS's hooke" % method)
    if "fibre" in overlaps:
        log = open(args.workdir + "/log.hooke_rest_fibre").read()
        checks.check("characteristicVelocity" in log,
                     "hooke: the log's material names the characteristicVelocity")


def rest_on_floor(args, checks):
    stl(args.workdir + "/floor.stl", square(0.05))
    for opts, name in (("compliance material", "material"), ("", "default"),
                       ("compliance auto", "rigid")):
        deck = header("-0.05 0.05 -0.05 0.05 -0.01 0.05") + one_sphere(0, 0, R) + [
            "timestep 0.0005", "fix g all gravity 9.81 vector 0 0 -1",
            "fix floor all mesh/surface file floor.stl type 2",
            "fix fc all fibre_contact wall mesh floor " + opts,
            "variable z equal z[1]",
            "thermo_style custom step v_z f_fc[3] f_fc[11] f_fc[1][3] f_fc[1][1]",
            "thermo_modify format float %.15g", "thermo 200", "run 2000"]
        run = e2e.run_lmp(args, "\n".join(deck) + "\n", "rest_" + name)
        if not checks.ran(run):
            continue
        overlap = R - run.last("z")
        if name != "rigid":
            hertz = (3 * mass() * G / (4 * y_eff() * math.sqrt(R))) ** (2.0 / 3.0)
            checks.agree(overlap, hertz, 0.01,
                         "%s: Hertz overlap on a mesh floor, Y* of sphere and mesh types" % name)
            checks.check("1 2: mu 0.5" in run.output and "restitution 0.3" in run.output,
                         "the log lists the property/global material per type pair")
        else:
            checks.check(abs(overlap) < 1e-4 * R, "rigid rows: the sphere rests at z = r",
                         "overlap %.3g r" % (overlap / R))
        checks.check(run.last("fc[11]") == 1, "one wall contact (the two triangles' shared "
                     "edge does not count twice)", "%g" % run.last("fc[11]"))
        checks.check(abs(run.last("fc[1][3]") + mass() * G) < 1e-3 * mass() * G and
                     abs(run.last("fc[1][1]")) < 1e-9, "the mesh's load f_fc[1][3] is -m g",
                     "%.9g vs %.9g" % (run.last("fc[1][3]"), -mass() * G))


def restitution_dashpot(args, checks):
    """LIGGGHTS's hertz dashpot from coefficientRestitution: alpha = sqrt(5) |ln e| /
    sqrt(ln^2 e + pi^2), and at e = 1 none (alpha 0), not the critical damping of a law
    without a dashpot."""
    stl(args.workdir + "/floor_e.stl", square(0.05))
    for e in (0.3, 1.0):
        deck = header("-0.05 0.05 -0.05 0.05 -0.01 0.05", restitution=e) + one_sphere(0, 0, R) + [
            "timestep 0.0005", "fix floor all mesh/surface file floor_e.stl type 2",
            "fix fc all fibre_contact wall mesh floor", "run 0"]
        run = e2e.run_lmp(args, "\n".join(deck) + "\n", "dashpot_%g" % e)
        if not checks.ran(run):
            continue
        ln = math.log(e)
        alpha = math.sqrt(5.0) * abs(ln) / math.sqrt(ln * ln + math.pi ** 2)
        logged = [float(line.split("alpha ")[1].rstrip(")"))
                  for line in run.output.splitlines() if "1 2: mu" in line and "alpha " in line]
        checks.check(logged and all(abs(x - alpha) <= 1e-5 * max(alpha, 1e-6) for x in logged),
                     "coefficientRestitution %g: the hertz dashpot alpha %.6g" % (e, alpha),
                     "logged %s" % logged)


def incline(args, checks):
    for theta_deg, mu, law in ((20.0, 0.5, "rolls"), (40.0, 0.1, "slides")):
        theta = math.radians(theta_deg)
        name = "incline_%d" % theta_deg
        stl(args.workdir + "/%s.stl" % name, square(0.6, angle=theta, half_y=0.05))
        # the sphere touches the plane at the origin's height, on the plane's normal
        n = (math.sin(theta), 0.0, math.cos(theta))
        deck = header("-0.7 0.7 -0.1 0.1 -0.6 0.6", mu=mu) + one_sphere(
            R * n[0] - 0.3 * math.cos(theta), 0, R * n[2] + 0.3 * math.sin(theta)) + [
            "timestep 0.0002", "fix g all gravity 9.81 vector 0 0 -1",
            "fix plane all mesh/surface file %s.stl type 2" % name,
            "fix fc all fibre_contact wall mesh plane",
            "variable v equal vx[1]*%.17g-vz[1]*%.17g" % (math.cos(theta), math.sin(theta)),
            "thermo_style custom step v_v", "thermo_modify format float %.15g",
            "thermo 250", "run 1500"]
        run = e2e.run_lmp(args, "\n".join(deck) + "\n", name)
        if not checks.ran(run):
            continue
        rows = {int(r["Step"]): r["v"] for r in run.thermo[-1]}
        a = (rows[1500] - rows[500]) / (1000 * 0.0002)
        expected = (5.0 / 7.0 * G * math.sin(theta) if law == "rolls"
                    else G * (math.sin(theta) - mu * math.cos(theta)))
        checks.agree(a, expected, 0.02, "mesh incline %g deg, mu %g: the sphere %s"
                     % (theta_deg, mu, law))


def conveyor(args, checks):
    u = 0.1
    stl(args.workdir + "/belt.stl", square(0.4, half_y=0.05))
    deck = header("-0.5 0.5 -0.1 0.1 -0.01 0.05") + one_sphere(-0.2, 0, R) + [
        "timestep 0.0002", "fix g all gravity 9.81 vector 0 0 -1",
        "fix belt all mesh/surface file belt.stl type 2",
        "fix move all move/mesh mesh belt linear %g 0 0" % u,
        "fix fc all fibre_contact wall mesh belt",
        "variable v equal vx[1]",
        "thermo_style custom step v_v", "thermo_modify format float %.15g",
        "thermo 500", "run 2500"]
    run = e2e.run_lmp(args, "\n".join(deck) + "\n", "conveyor")
    if checks.ran(run):
        checks.agree(run.last("v"), 2.0 / 7.0 * u, 0.02,
                     "a sphere on a conveyor mesh (fix move/mesh) is carried at 2/7 U")


def cube_drop(args, checks):
    lo, hi = (-0.02, -0.02, 0.0), (0.02, 0.02, 0.04)
    stl(args.workdir + "/cube.stl", cube(lo, hi))
    deck = header("-0.1 0.1 -0.1 0.1 -0.001 0.1")
    spots = [(0.0, 0.0), (0.02, 0.0), (0.02, 0.02), (-0.01, 0.02), (0.021, -0.02)]
    for k, (x, y) in enumerate(spots):
        deck += ["create_atoms 1 single %g %g %g units box" % (x, y, 0.06 + 0.015 * k)]
    deck += ["set type 1 diameter %g density %g" % (2 * R, RHO),
             "timestep 0.0002", "fix g all gravity 9.81 vector 0 0 -1",
             "fix box all mesh/surface file cube.stl type 2",
             # rigid rows: the geometry alone keeps the spheres out
             "fix fc all fibre_contact wall mesh box wall zplane 0 NULL compliance auto",
             "dump d all custom 100 cube.dump id x y z",
             "dump_modify d sort id",
             "thermo_style custom step ke", "thermo 500", "run 6000"]
    run = e2e.run_lmp(args, "\n".join(deck) + "\n", "cube")
    if not checks.ran(run):
        return
    frames = e2e.parse_dump(args.workdir + "/cube.dump")
    closest = float("inf")
    for _, columns, rows in frames:
        ix, iy, iz = columns.index("x"), columns.index("y"), columns.index("z")
        for row in rows:
            x, y, z = row[ix], row[iy], row[iz]
            # distance from the centre to the cube (0 inside)
            d = [max(lo[i] - c, 0.0, c - hi[i]) for i, c in enumerate((x, y, z))]
            closest = min(closest, math.sqrt(sum(v * v for v in d)))
    checks.check(closest >= 0.999 * R, "spheres dropped on a cube mesh's face, edges and "
                 "corner never enter it", "closest centre %.4g r" % (closest / R))
    checks.check(run.last("KinEng") < 1e-6, "they come to rest", "KE %g" % run.last("KinEng"))
    checks.check("wall mesh box: 12 triangles, 0 open edges (a closed surface)" in run.output,
                 "the log describes the cube mesh as closed")


def pile_deck(np_grid=None):
    deck = header("-0.03 0.03 -0.03 0.03 -0.001 0.12", processors=np_grid)
    deck += ["lattice sc 0.0104", "region fill block -0.02 0.02 -0.02 0.02 0.01 0.09 units box",
             "create_atoms 1 region fill", "set type 1 diameter %g density %g" % (2 * R, RHO),
             "timestep 0.0005",
             "fix g all gravity 9.81 vector 0 0 -1",
             "fix box all mesh/surface file box.stl type 2",
             "fix fc all fibre_contact wall mesh box solver cg tol none linear_tol 1e-8 sweeps 400 "
             "sweep_tol 1e-8",
             "compute c all com",
             "thermo_style custom step atoms ke c_c[1] c_c[2] c_c[3] f_fc[3]",
             "thermo_modify format float %.15g", "thermo 100"]
    return deck


def parallel_and_restart(args, checks):
    # an open box: floor and four sides
    tris = [t for t in cube((-0.03, -0.03, 0.0), (0.03, 0.03, 0.11))]
    tris = [t for t in tris if not all(abs(p[2] - 0.11) < 1e-12 for p in t)]  # no lid
    stl(args.workdir + "/box.stl", tris)
    serial = e2e.run_lmp(args, "\n".join(pile_deck() + ["run 250"]) + "\n", "pile_np1")
    para = e2e.run_lmp(args, "\n".join(pile_deck("2 1 1") + ["run 250"]) + "\n", "pile_np2",
                       np=2)
    if checks.ran(serial) and checks.ran(para):
        checks.check(serial.last("Atoms") == para.last("Atoms"), "np 2 keeps every sphere")
        checks.check("wall mesh box: 10 triangles, 4 open edges" in para.output,
                     "np 2: the log counts the open box's 4 open edges over both processes")
        for col in ("c[1]", "c[2]", "c[3]"):
            checks.check(abs(serial.last(col) - para.last(col)) < 1e-9,
                         "np 2: centre of mass %s as in serial" % col,
                         "%.9g vs %.9g" % (serial.last(col), para.last(col)))
        checks.check(abs(serial.last("KinEng") - para.last("KinEng")) < 1e-12,
                     "np 2: kinetic energy as in serial (the pile's m g r is 5e-3 J)",
                     "%.3g vs %.3g J" % (serial.last("KinEng"), para.last("KinEng")))
    first = e2e.run_lmp(args, "\n".join(pile_deck() + ["run 150", "write_restart pile.restart"])
                        + "\n", "pile_first")
    cont = ["atom_style granular", "atom_modify map array", "communicate single vel yes",
            "newton off", "read_restart pile.restart", "neighbor 0.002 bin",
            "neigh_modify delay 0"] + [
        ln for ln in header("-0.03 0.03 -0.03 0.03 -0.001 0.12")
        if ln.startswith("fix m") or ln.startswith("pair_")] + [
        "fix g all gravity 9.81 vector 0 0 -1",
        "fix box all mesh/surface file box.stl type 2",
        "fix fc all fibre_contact wall mesh box solver cg tol none linear_tol 1e-8 sweeps 400 "
        "sweep_tol 1e-8",
        "timestep 0.0005", "compute c all com",
        "thermo_style custom step atoms ke c_c[1] c_c[2] c_c[3] f_fc[3]",
        "thermo_modify format float %.15g", "thermo 100", "run 100"]
    second = e2e.run_lmp(args, "\n".join(cont) + "\n", "pile_second")
    if checks.ran(first) and checks.ran(second) and checks.ran(serial):
        checks.check(abs(second.last("c[3]") - serial.last("c[3]")) < 1e-9,
                     "restart: the continued run ends at the uninterrupted run's centre of mass",
                     "%.9g vs %.9g" % (second.last("c[3]"), serial.last("c[3]")))


def bad_input(args, checks):
    stl(args.workdir + "/floor.stl", square(0.05))
    base = header("-0.05 0.05 -0.05 0.05 -0.01 0.05") + one_sphere(0, 0, 0.01) + [
        "timestep 0.0005", "fix floor all mesh/surface file floor.stl type 2"]
    cases = [
        ("nosuch", base + ["fix fc all fibre_contact wall mesh nowhere"],
         "'wall mesh nowhere': no fix with ID nowhere"),
        ("notmesh", base + ["fix fc all fibre_contact wall mesh m1"],
         "fix m1 is a property/global, expected a fix mesh/surface"),
        ("region", base + ["region r block -1 1 -1 1 -1 1 units box",
                           "fix fc all fibre_contact wall region r"],
         "LIGGGHTS regions are not walls for this fix"),
        # LIGGGHTS's pair style or this fix, whichever reads the table first, names it
        ("nofriction", [ln for ln in base if "coefficientFriction" not in ln] +
         ["fix fc all fibre_contact wall mesh floor"], "coefficientFriction"),
        ("shape", [ln.replace("peratomtypepair 2 0.5 0.5 0.5 0.5", "peratomtype 0.5 0.5")
                   for ln in base] + ["fix fc all fibre_contact wall mesh floor"],
         "peratomtypepair style required for fix property/global variable "
         "coefficientFriction"),
    ]
    for name, lines, message in cases:
        run = e2e.run_lmp(args, "\n".join(lines + ["run 10"]) + "\n", "bad_" + name)
        checks.check(run.rc != 0 and message in run.output,
                     "bad input '%s' is an error naming it" % name,
                     "rc %d, %s" % (run.rc, run.error_line() or run.output[-300:]))


def main():
    args = e2e.parse_args()
    checks = e2e.Checks("LIGGGHTS front end: mesh walls, materials, MPI, restart, bad input")
    rest_on_floor(args, checks)
    hooke_rest(args, checks)
    restitution_dashpot(args, checks)
    incline(args, checks)
    conveyor(args, checks)
    cube_drop(args, checks)
    parallel_and_restart(args, checks)
    bad_input(args, checks)
    checks.close()


if __name__ == "__main__":
    main()
