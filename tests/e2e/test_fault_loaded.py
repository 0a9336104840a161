"""Faults: a sphere created inside a soft bed under load. A simple cubic bed 3 x 3 wide and 30
deep (d = 1, 2500 kg/m^3, hertz/material E = 1e7, Mindlin, tsuji; the step 0.002 s) settles
under gravity for 0.3 s: while its columns' load grows, many contacts overlap more than their
last load explains (shallow penetrations, opened by their rows). Then one sphere is created where
four columns meet, 29% of a diameter into each, and the run goes on for 1.5 s.

Pass rule, serial and on two processes: the created sphere's deep contacts, and only they, are
split (f_ID[22] at least 1 and at most 16: its own contacts and those its displacement meets),
nothing is lost or NaN, and no sphere is faster than the recovery speed plus gravity's. Before
an elastic penetration's split was its own (Contact::split), the recovery's floor split every
shallow penetration of the bed while one was opened: 40 to 45 here (created at 0.1 and 0.3 s),
and 7,600 at each step in a bed 80 layers deep, whose springs lost their loads' overlap while
the recovery's solve ran over every contact.
"""

import fibre_e2e as e2e

LAW = "hertz/material 1e7 0.3 0.3 tangential mindlin NULL 1.0 0.5 damping tsuji"
WALL = "granular " + LAW

DECK = e2e.bed_under_gravity("0 3 0 3 0 40", 3, 30, LAW, "2500", "0.002", "{procs}") + """
fix f all fibre_contact wall {W} xplane 0 3 wall {W} yplane 0 3 wall {W} zplane 0 NULL
variable speed atom sqrt(vx*vx+vy*vy+vz*vz)
compute fastest all reduce max v_speed
thermo_style custom step atoms ke c_fastest f_f[7] f_f[22]
thermo_modify lost warn format float %.10g
thermo 100
run 150
variable zin equal bound(all,zmax)/2
create_atoms 1 single 1.0 1.0 ${{zin}} units box
set type 1 diameter 1.0
set type 1 density 2500
thermo 5
run 750
"""


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("faults: a sphere created inside a soft bed under load")
    recovery = 0.01 * 0.5 / 0.002  # the automatic recovery speed: 0.01 r_min / h
    for np in (1, 2):
        name = "loaded_np%d" % np
        deck = DECK.format(procs="1 1 2" if np == 2 else "1 1 1", W=WALL)
        run = e2e.run_lmp(args, deck, name, np=np)
        if not ck.ran(run):
            continue
        what = "np %d: " % np
        bed = run.column("Atoms", block=0)[-1]
        atoms = run.column("Atoms", block=1)
        split = run.column("f_f[22]", block=1)
        fastest = run.column("c_fastest", block=1)
        ck.check(min(atoms) == max(atoms) == bed + 1 and e2e.finite(fastest),
                 what + "nothing lost, nothing NaN", "%d to %d atoms" % (min(atoms), max(atoms)))
        ck.check(max(split) >= 1, what + "the created sphere's contacts are split",
                 "at most %d split" % max(split))
        ck.check(max(split) <= 16, what + "and no other contact of the loaded bed",
                 "at most %d split" % max(split))
        ck.check(max(fastest) <= recovery + 9.81 * 1.5,
                 what + "no sphere faster than the recovery speed and gravity",
                 "%.4g m/s" % max(fastest))
    ck.close()


if __name__ == "__main__":
    main()
