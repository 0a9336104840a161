"""Faults: a sphere at 1e3 m/s against a wall and into a bed (hertz/material E = 1e8, Mindlin,
tsuji damping, d = 1, 2500 kg/m^3, no gravity, a closed box of walls of the same material),
at a step of 1e-3 s: the sphere moves a diameter a step, more than the neighbour skin (0.3)
unless the skin is raised (1.5), and the fix warns of it.

Pass rule, compliance material and auto, the skin as typed and raised, serial and on two
processes: nothing lost or NaN; no sphere below the floor or above the ceiling (no tunnelling);
no sphere faster than the shot and the kinetic energy never above its start (the contacts only
dissipate); the skin's warning where the skin is short. Native LAMMPS at 1e-5 s runs the bed
case for the record (doc/validation.md).
"""

import fibre_e2e as e2e

LAW = "hertz/material 1e8 0.3 0.3 tangential mindlin NULL 1.0 0.5 damping tsuji"
WALL = "wall granular " + LAW

DECK = "units si\n" + "\n".join(e2e.sphere_box("0 6 0 6 0 11", processors="{procs}")) + """
{bed}
create_atoms 1 single 3.0 3.0 6.0 units box
set type 1 diameter 1.0
set type 1 density 2500
group shot id {shot}
velocity shot set 0 0 -1000 units box
pair_style granular
pair_coeff * * """ + LAW + """
neighbor {skin} bin
neigh_modify every 1 delay 0
timestep {dt}
{integrate}
variable speed atom sqrt(vx*vx+vy*vy+vz*vz)
compute fastest all reduce max v_speed
compute lowest all reduce min z
compute highest all reduce max z
compute kea all ke/atom
compute energy all reduce sum c_kea
thermo_style custom step atoms c_energy c_fastest c_lowest c_highest
thermo_modify lost warn norm no format float %.10g
thermo {every}
run {steps}
"""

BED = e2e.cubic_bed(6, 3)


def integrate(method, extra):
    if method == "fibre":
        return "fix f all fibre_contact %s xplane 0 6 %s yplane 0 6 %s zplane 0 11 %s" % (
            WALL, WALL, WALL, extra)
    w = "fix w%s all wall/gran granular " + LAW + " %s"
    return "\n".join(["fix n all nve/sphere", w % ("x", "xplane 0 6"), w % ("y", "yplane 0 6"),
                      w % ("z", "zplane 0 11")])


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("faults: a sphere at 1e3 m/s against a wall and into a bed")
    for target, shot in (("wall", 1), ("bed", 109)):
        for extra, skin, np in (("", 0.3, 1), ("", 1.5, 1), ("compliance auto", 0.3, 1),
                                ("", 0.3, 2), ("compliance auto", 1.5, 2)):
            if target == "wall" and np == 2:
                continue
            deck = DECK.format(procs="2 1 1" if np == 2 else "1 1 1",
                               bed=BED if target == "bed" else "", shot=shot, skin=skin,
                               dt=1e-3, integrate=integrate("fibre", extra), every=5, steps=400)
            name = "%s_%s_skin%g_np%d" % (target, "auto" if extra else "material", skin, np)
            run = e2e.run_lmp(args, deck, name, np=np)
            what = "%s, %s, skin %g, np %d: " % (target, extra or "compliance material", skin, np)
            if not ck.ran(run):
                continue
            atoms, speeds, ke = run.column("Atoms"), run.column("c_fastest"), run.column("c_energy")
            ck.check(min(atoms) == max(atoms) and e2e.finite(speeds + ke),
                     what + "nothing lost, nothing NaN",
                     "%d to %d atoms" % (min(atoms), max(atoms)))
            ck.check(min(run.column("c_lowest")) > 0.0 and max(run.column("c_highest")) < 11.0,
                     what + "no sphere through the floor or the ceiling",
                     "centres from %.4g to %.4g" % (min(run.column("c_lowest")),
                                                    max(run.column("c_highest"))))
            ck.check(max(speeds) <= 1000.0 * (1 + 1e-9) and max(ke) <= ke[0] * (1 + 1e-9),
                     what + "no sphere faster than the shot, no energy gained",
                     "fastest %.6g m/s, kinetic energy at most %.4g of its start"
                     % (max(speeds), max(ke) / ke[0]))
            warned = "more than the neighbor skin" in run.log
            ck.check(warned == (skin < 1.0), what + "the skin's warning where the skin is short")
    # native at 1e-5 s, for the record
    deck = DECK.format(procs="1 1 1", bed=BED, shot=109, skin=0.3, dt=1e-5,
                       integrate=integrate("native", ""), every=500, steps=40000)
    run = e2e.run_lmp(args, deck, "bed_native", np=1)
    if run.rc == 0 and run.column("Atoms"):
        print("native bed at 1e-5 s: %d to %d atoms, fastest %.4g m/s, centres from %.4g to %.4g"
              % (min(run.column("Atoms")), max(run.column("Atoms")), max(run.column("c_fastest")),
                 min(run.column("c_lowest")), max(run.column("c_highest"))))
    ck.close()


if __name__ == "__main__":
    main()
