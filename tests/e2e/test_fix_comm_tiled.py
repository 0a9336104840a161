"""Load balancing: comm_style tiled with fix balance rcb, and comm_style brick with fix balance
shift, against the serial run. A dam break: an fcc block of 640 spheres (d 0.90 to 0.98,
density 2500, hertz/material E = 1e7, Mindlin, SDS rolling, tsuji, walls of the same material)
in the left third of a walled box 25 long collapses to the right for 1 simulated second at
0.002 s. Without balancing, brick's even cut at x = 12 leaves every sphere on one process; the
balancers split them. A second deck, periodic along x with the block filling the period,
runs on three processes under rcb (ghosts that are other processes' atoms and periodic images
of the process's own).

Pass rule: nothing lost or NaN; each balancer leaves at most 60% of the spheres on one
process; at every output the kinetic energy within 2% of the serial run's peak and the centre
of mass within 0.5% (the processes change only the sweeps' order, within the solver's tol; the
collapse is not chaotic in its first second).
"""

import fibre_e2e as e2e

LAW = ("hertz/material 1e7 0.3 0.3 tangential mindlin NULL 1.0 0.5 "
       "rolling sds 1e3 10 0.1 damping tsuji")

DECK = """
variable a equal sqrt(2.0)
atom_style sphere
atom_modify map array
boundary {boundary}
newton off
comm_modify vel yes
{comm}
lattice fcc ${{a}}
region box block -0.6 {xhi} -0.6 6.5 -0.6 12 units box
create_box 1 box
region block block 0 4.99 0 3.99 0 7.99 units lattice
create_atoms 1 region block
variable d atom 0.90+0.08*random(0,1,4767)
set group all diameter v_d
set group all density 2500
pair_style granular
pair_coeff * * {law}
neighbor 0.1 bin
neigh_modify delay 0 every 1 check yes
fix grav all gravity 9.81 vector 0 0 -1
timestep 0.002
fix fc all fibre_contact {walls}
{balance}
variable xc equal xcm(all,x)
variable zc equal xcm(all,z)
variable most equal {most}
thermo_style custom step atoms ke v_xc v_zc f_fc[3] v_most
thermo_modify lost warn format float %.12g
thermo 50
run 500
"""

BALANCE = {"tiled": ("comm_style tiled", "fix bal all balance 25 1.05 rcb"),
           "shift": ("", "fix bal all balance 25 1.05 shift x 10 1.05")}


def deck(periodic, style):
    comm, balance = BALANCE.get(style, ("", ""))
    walls = ["yplane -0.5 6.4", "zplane -0.5 NULL"]
    if not periodic:
        walls.insert(0, "xplane -0.5 24.4")
    return DECK.format(boundary="p f f" if periodic else "f f f", comm=comm, balance=balance,
                       xhi="6.47" if periodic else "24.5", law=LAW,
                       walls=" ".join("wall granular %s %s" % (LAW, w) for w in walls),
                       most="f_bal[1]" if balance else "count(all)")


def compare(ck, what, run, serial):
    ke, ke0 = run.column("KinEng")[1:], serial.column("KinEng")[1:]
    ck.check(len(ke) == len(ke0) and len(ke) > 0, what + "as many outputs as serial")
    dke = max(abs(a - b) for a, b in zip(ke, ke0)) / max(ke0)
    ck.check(dke < 0.02, what + "kinetic energy within 2% of serial's peak", "%.3g" % dke)
    for col in ("v_xc", "v_zc"):
        d = max(abs(a - b) / abs(b) for a, b in zip(run.column(col), serial.column(col)))
        ck.check(d < 0.005, what + "centre %s within 0.5%% of serial's" % col[-2], "%.3g" % d)


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("comm_style tiled and fix balance against serial")
    for periodic, runs in ((False, (("brick", 1), ("tiled", 2), ("shift", 2))),
                           (True, (("brick", 1), ("tiled", 3)))):
        serial = None
        for style, np in runs:
            name = "%s_%s_np%d" % ("periodic" if periodic else "dam", style, np)
            run = e2e.run_lmp(args, deck(periodic, style), name, np=np)
            what = name + ": "
            if not ck.ran(run):
                continue
            ck.check(min(run.column("Atoms")) == 640 and e2e.finite(run.column("KinEng")),
                     what + "nothing lost or NaN")
            if np == 1:
                serial = run
                continue
            most = run.column("v_most")[-1]
            ck.check(most <= 0.6 * 640, what + "at most 60% of the spheres on one process",
                     "%d" % most)
            if serial:
                compare(ck, what, run, serial)
    ck.close()


if __name__ == "__main__":
    main()
