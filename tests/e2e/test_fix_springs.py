"""Elastic tangential and rolling rows (compliance material): a pulled sphere on a spring.

A sphere (diameter 1, density 1) rests on a plane under gravity with pair_style granular
`hertz` (explicit k_n), `tangential mindlin` (explicit k_t) and `rolling sds`, constants that
fix wall/gran and the pair style read alike, so native LAMMPS is a twin of the same material.
After 2 s at rest it is pulled sideways at its centre by F = 0.15 m g, below the sliding
(mu m g) and the rolling (mu_roll m g) limits, for 3 s, then let go for 3 s.

At rest under the pull the tangential spring at the contact point carries F and the rolling
spring the torque F r: the centre moves by x = F / (k_t a) + F / k_roll (a = sqrt(r delta)
the contact radius at Hertz's overlap delta, k_roll r_eff^2 per unit angle with r_eff = r),
and when the pull stops both springs return it to where it started. Checked against that
formula and against native LAMMPS (fix nve/sphere and fix wall/gran, 10x smaller step), on
one process and on two (the sphere sits on the boundary between them). A rigid-plastic
tangential row would not move at all; a compliance without the displacement history would
creep without bound.
"""

import math

import fibre_e2e as e2e

G = 9.81
R = 0.5
MASS = math.pi / 6.0
KN, KT, KROLL = 1.0e5, 2.0e4, 1.0e3
MU, MUROLL = 0.5, 0.3
PULL = 0.15 * MASS * G
MATERIAL = ("hertz %g 0.3 tangential mindlin %g 1.0 %g rolling sds %g 10 %g damping tsuji"
            % (KN, KT, MU, KROLL, MUROLL))

DECK = """atom_style sphere
atom_modify map array
boundary f f f
newton off
comm_modify vel yes
{processors}
region box block -5 5 -5 5 0 5 units box
create_box 1 box
create_atoms 1 single 0 0 0.5 units box
set atom 1 diameter 1.0 density 1.0
pair_style granular
pair_coeff * * {material}
neighbor 0.2 bin
fix g all gravity {g} vector 0 0 -1
{integrate}
variable x equal x[1]
thermo_style custom step v_x
thermo_modify format float %.12g
thermo {every}
run {rest}
fix push all addforce {pull:.12g} 0 0
run {held}
unfix push
run {held}
"""

FIBRE = "timestep 1e-3\nfix fc all fibre_contact wall zplane 0.0 NULL compliance material"
NATIVE = ("timestep 1e-4\nfix i all nve/sphere\n"
          "fix w all wall/gran granular {material} zplane 0.0 NULL")


def deck(native, np):
    steps = 10000 if native else 1000  # one second
    integrate = NATIVE.format(material=MATERIAL) if native else FIBRE
    return DECK.format(processors="processors 2 1 1" if np == 2 else "", material=MATERIAL,
                       g=G, integrate=integrate, every=steps, rest=2 * steps, pull=PULL,
                       held=3 * steps)


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("elastic tangential and rolling rows: a pulled sphere on its springs")
    # Hertz: m g = k_n sqrt(r_eff delta) delta with r_eff = r for a plane
    delta = (MASS * G / (KN * math.sqrt(R))) ** (2.0 / 3.0)
    a = math.sqrt(R * delta)
    expected = PULL / (KT * a) + PULL / KROLL
    runs = [("native", True, 1), ("fibre_np1", False, 1), ("fibre_np2", False, 2)]
    for tag, native, np in runs:
        run = e2e.run_lmp(args, deck(native, np), "springs_" + tag, np=np)
        if not ck.ran(run):
            continue
        held = run.last("v_x", block=1)
        released = run.last("v_x", block=2)
        ck.agree(held, expected, 0.01, "%s: pulled, the centre moves by F / (k_t a) + F / k_roll"
                 % tag, "%.6g")
        ck.check(abs(released) < 0.02 * expected,
                 "%s: let go, the springs bring it back to where it started" % tag,
                 "x %.3g after release, %.3g under the pull" % (released, held))
    ck.close()


if __name__ == "__main__":
    main()
