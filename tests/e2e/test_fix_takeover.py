"""Taking over a state with deep overlaps (issue #14, item 5): no sphere is launched.

A 4 x 4 x 4 simple cubic pile of spheres of diameter 1 at spacing 0.9 (overlaps of 10% of a
diameter, 5% against the floor), as a soft native pile or a careless read_data leaves them, is
continued under gravity (open box: the pile may spread). With the default recovery_speed (auto: 0.01 r_min / dt = 1 m/s here)
the overlaps close over about 20 steps, no sphere moves faster than the column of bounded
contacts behind it allows (five vertically and three in x and y: 6.6 m/s), the deepest overlap ends below 1% of a diameter, and the
fix warns about the deep overlaps at the start of the run. With `recovery_speed none` SPOOK
closes every overlap within a few steps and launches the top spheres at more than 3 times
that speed. Serial and on two processes.
"""

import re

import fibre_e2e as e2e

DECK = """atom_style sphere
boundary f f f
newton off
processors * 1 1
comm_modify vel yes
region box block -4 8 -4 8 0 30 units box
create_box 1 box
lattice sc 1.3717421125  # spacing 0.9 (reduced density 1 / 0.9^3)
region pile block 0 3.5 0 3.5 0 3.5 units box
create_atoms 1 region pile units box
displace_atoms all move 0.0 0.0 0.45 units box
reset_atom_ids sort yes
set type 1 diameter 1.0 density 1.0
pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0
pair_coeff * *
neighbor 0.3 bin
timestep 0.005
fix g all gravity 9.81 vector 0 0 -1
fix fc all fibre_contact mu 0.5 wall zplane 0.0 NULL {opts}
compute v all property/atom vx vy vz
variable speed atom sqrt(vx*vx+vy*vy+vz*vz)
compute vmax all reduce max v_speed
thermo_style custom step ke c_vmax f_fc[3] f_fc[7]
thermo_modify lost ignore  # recovery_speed none launches spheres out of the box
thermo 5
run 200
"""


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("take-over: deep initial overlaps are removed at a bounded speed")
    for np in (1, 2):
        tag = "np%d" % np
        bounded = e2e.run_lmp(args, DECK.format(opts=""), "takeover_auto_" + tag, np=np)
        free = e2e.run_lmp(args, DECK.format(opts="recovery_speed none"),
                           "takeover_none_" + tag, np=np)
        if not (ck.ran(bounded) and ck.ran(free)):
            continue
        v_auto = max(bounded.column("c_vmax"))
        v_none = max(free.column("c_vmax"))
        # a corner sphere on top is pushed through five contacts vertically (floor and four
        # spheres) and up to three in x and in y, each separating at no more than 1 m/s:
        # sqrt(5^2 + 3^2 + 3^2) = 6.56 m/s
        ck.check(v_auto < 6.56 + 9.81 * 0.005 * 5,
                 "%s: auto: no sphere faster than its bounded contacts allow" % tag,
                 "largest speed %.3g m/s" % v_auto)
        ck.check(bounded.last("f_fc[7]") < 0.01,
                 "%s: auto: the overlaps close (deepest below 1%% of a diameter)" % tag,
                 "deepest overlap %.3g at the end" % bounded.last("f_fc[7]"))
        ck.check(re.search(r"WARNING: Fix fibre_contact: the run starts with overlaps of up to "
                           r"1\d(\.\d+)?% of a diameter", bounded.output) is not None,
                 "%s: auto: the deep overlaps are warned about" % tag)
        ck.check(v_none > 3.0 * v_auto,
                 "%s: recovery_speed none launches spheres (the bound matters)" % tag,
                 "largest speed %.3g m/s against %.3g" % (v_none, v_auto))
    ck.close()


if __name__ == "__main__":
    main()
