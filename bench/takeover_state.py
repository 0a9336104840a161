#!/usr/bin/env python3
"""A cold start: the first step of fix fibre_contact taking over a native pile, exported.

tests/data/pile400.dump holds 400 Hertz spheres (radii 0.25 to 0.5) that native LAMMPS poured
and settled in an 8 x 8 box (tests/data/in.pile400). This writes them as a data file, continues
them under the fix for one step (hertz/material E with Mindlin friction mu and Tsuji damping,
the box's floor and side walls of the same material, step 1e-3, one substep) and exports that
step: WORK/takeover.1.0.sys and .lambda, whose warm start is zero. `fibre_accuracy` replays it.

Usage: bench/takeover_state.py [--lmp build/fix/lmp_fibre] [--work /tmp/fibre_takeover]
                               [--E 1e8] [--mu 0.5] [--keywords "compliance auto"]
"""

import argparse
import math
import os
import subprocess
import sys

SRC = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(SRC, "tools"))
from lammps_runs import lmp_env, parse_dump  # noqa: E402

DECK = """units si
atom_style sphere
boundary f f f
newton off
comm_modify vel yes
read_data {data}
neighbor 0.5 bin
neigh_modify delay 0
pair_style granular
pair_coeff * * hertz/material {E} 0.1 0.2857 tangential mindlin NULL 1.0 {mu} damping tsuji
fix g all gravity 9.81 vector 0 0 -1
timestep 1e-3
fix fc all fibre_contact wall type 1 zplane 0.0 NULL wall type 1 xplane 0.0 8.0 &
    wall type 1 yplane 0.0 8.0 substeps 1 {keywords} export 1 takeover
thermo_style custom step ke f_fc[3] f_fc[14] f_fc[16]
thermo 1
run 1
"""


def write_data(dump, path):
    _, columns, rows = parse_dump(dump)[-1]
    out = ["pile400, settled by native LAMMPS", "", "%d atoms" % len(rows), "1 atom types",
           "0 8 xlo xhi", "0 8 ylo yhi", "0 40 zlo zhi", "", "Atoms # sphere", ""]
    for row in rows:  # the data file wants diameter and density
        a = dict(zip(columns, row))
        density = a["mass"] / (4.0 / 3.0 * math.pi * a["radius"] ** 3)
        out.append("%d 1 %r %r %r %r %r" % (a["id"], 2 * a["radius"], density, a["x"], a["y"],
                                            a["z"]))
    open(path, "w").write("\n".join(out) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--lmp", default=os.path.join(SRC, "build/fix/lmp_fibre"))
    ap.add_argument("--work", default="/tmp/fibre_takeover")
    ap.add_argument("--E", default="1e8")
    ap.add_argument("--mu", default="0.5")
    ap.add_argument("--keywords", default="compliance auto")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    data = os.path.join(a.work, "pile400.data")
    write_data(os.path.join(SRC, "tests/data/pile400.dump"), data)
    deck = os.path.join(a.work, "in.takeover")
    open(deck, "w").write(DECK.format(data=data, E=a.E, mu=a.mu, keywords=a.keywords))
    subprocess.run([a.lmp, "-in", deck, "-log", "log.takeover", "-screen", "none"], cwd=a.work,
                   env=lmp_env(), check=True)
    print("state: %s" % os.path.join(a.work, "takeover.1.0"))


if __name__ == "__main__":
    main()
