#!/usr/bin/env python3
"""The official LAMMPS granular decks beside their fix fibre_contact conversions.

Each native deck is read from Debian's lammps-examples (/usr/share/lammps/examples) or
liggghts-doc (LIGGGHTS's public tutorials); its conversion is in.NAME.fibre beside this
script (every changed line marked "fibre:"). Both twins run with lmp_fibre (lmp plus the fix)
or liggghts_fibre (liggghts plus the fix), one at a time, and the script prints each deck's
figure, native against fix, with the wall seconds.

  python3 examples/official/official.py [--lmp build/fix/lmp_fibre] [--np 1] [--workdir W]
"""

import argparse
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools"))
from lammps_runs import lmp_env, mpi_prefix, parse_thermo  # noqa: E402

EXAMPLES = "/usr/share/lammps/examples"
LIGGGHTS_EXAMPLES = "/usr/share/doc/liggghts/examples/LIGGGHTS/Tutorials_public"
UNIT_AXIS = "0.57735026918962573 " * 3

# pour.flatwall's figure: per type the count, centre height, radius of gyration and lowest
# centre (a sphere in the floor sits below its radius, 0.25 at least)
FLATWALL_FIGURES = """
group t1 type 1
group t2 type 2
variable n1 equal count(t1)
variable n2 equal count(t2)
variable z1 equal xcm(t1,z)
variable z2 equal xcm(t2,z)
variable g1 equal gyration(t1)
variable g2 equal gyration(t2)
variable zmin1 equal bound(t1,zmin)
variable zmin2 equal bound(t2,zmin)
print "FIGURES n1 ${n1} n2 ${n2} z1 ${z1} z2 ${z2} g1 ${g1} g2 ${g2} zmin1 ${zmin1} zmin2 ${zmin2}"
"""


def box_deck(text):
    """granregion.box: the fifth stage's axis typed as a unit vector. LAMMPS's region velocity
    is the angular speed times the axis as typed, so fix wall/gran/region spins the native
    walls sqrt(3) times too fast about '1 1 1'; fix fibre_contact uses the unit axis."""
    return text.replace("rotate v_theta 0 0 0 1 1 1", "rotate v_theta 0 0 0 " + UNIT_AXIS)


def box_figures(run):
    """Atoms after each of the five stages; mean temperature of stages 2 and 4 (rotating)."""
    blocks = run["thermo"]
    out = {"atoms": [b[-1]["Atoms"] for b in blocks]}
    for k in (1, 3):
        rows = blocks[k][1:] if len(blocks) > k else []
        out["T%d" % (k + 1)] = sum(r["Temp"] for r in rows) / len(rows) if rows else float("nan")
    return out


def printed_figures(run):
    m = re.search(r"^FIGURES (.*)$", run["log"], re.M)
    if not m:
        return {}
    words = m.group(1).split()
    return {words[i]: float(words[i + 1]) for i in range(0, len(words), 2)}


# the cohesion tutorial's figure: the bed's centre height (cohesion holds it up)
BED_FIGURES = """
variable na equal count(all)
variable zc equal xcm(all,z)
print "FIGURES atoms ${na} zc ${zc}"
"""


# pour.drum's figure: the spheres left, and where the bed's centre sits in the drum rotating
# about z with gravity along -y (its x shift is the bed climbing the rising wall)
DRUM_FIGURES = """
variable na equal count(all)
variable xc equal xcm(all,x)
variable yc equal xcm(all,y)
variable zc equal xcm(all,z)
print "FIGURES atoms ${na} xc ${xc} yc ${yc} zc ${zc}"
"""


def mixer_deck(text):
    """granregion.mixer with its thermo extended: rotational energy, the bed's centre height
    and the highest grain."""
    old = "thermo_style\tcustom step cpu atoms ke v_theta"
    assert old in text
    return text.replace(old, "compute rke all erotate/sphere\nvariable zc equal xcm(all,z)\n"
                        "variable zmax equal bound(all,zmax)\n" + old + " c_rke v_zc v_zmax")


def mixer_figures(run):
    """Spheres at the end; over the second half of the mixing stage (the second run; its
    first half still has the last insertion falling) the mean kinetic and rotational energy
    and bed centre height, and the highest grain."""
    blocks = run["thermo"]
    if len(blocks) < 2:
        return {}
    rows = blocks[1][len(blocks[1]) // 2:]
    mean = lambda key: sum(r[key] for r in rows) / len(rows)  # noqa: E731
    return {"atoms": blocks[-1][-1]["Atoms"], "ke": mean("KinEng"), "rke": mean("c_rke"),
            "zc": mean("v_zc"), "zmax": max(r["v_zmax"] for r in rows)}


def pour_figures(run):
    """pour (a chute): spheres at the end, and over the flow (the second run, gravity tilted
    26 degrees) the mean kinetic and rotational energy, which grow as the flow speeds up."""
    blocks = run["thermo"]
    if len(blocks) < 2:
        return {}
    rows = blocks[1][1:]
    mean = lambda key: sum(r[key] for r in rows) / len(rows) if rows else float("nan")  # noqa
    return {"atoms": blocks[-1][-1]["Atoms"], "ke": mean("KinEng"), "rke": mean("c_1")}


def shortened(name, text):
    """The deck with fewer steps, for the tests (pour: 10000 steps of insertion, 8000 of flow,
    thermo every 500)."""
    if name != "pour":
        return text
    first = text.index("run\t\t25000")
    text = text[:first] + "run 10000" + text[first + len("run\t\t25000"):]
    text = text.replace("run\t\t25000", "run 8000").replace("thermo\t\t1000", "thermo 500")
    return text


def with_drum_figures(text):
    return text + DRUM_FIGURES


def same(text):
    return text


def with_figures(text):
    return text + FLATWALL_FIGURES


def bed_deck(text):
    """The cohesion tutorial without its VTK dump, with the bed's figure."""
    return re.sub(r"(?m)^dump\s.*$", "", text) + BED_FIGURES


# name: (host, native path, the native twin's edit, both twins' edit, figures)
DECKS = {
    "granregion.box": ("lammps", "granregion/in.granregion.box", box_deck, same, box_figures),
    "pour.flatwall": ("lammps", "granular/in.pour.flatwall", same, with_figures,
                      printed_figures),
    "granregion.mixer": ("lammps", "granregion/in.granregion.mixer", same, mixer_deck,
                         mixer_figures),
    "pour.drum": ("lammps", "granular/in.pour.drum", same, with_drum_figures,
                  printed_figures),
    "pour": ("lammps", "pour/in.pour", same, same, pour_figures),
    "cohesion.noCohesion": ("liggghts", "cohesion/in.noCohesion", same, bed_deck,
                            printed_figures),
    "cohesion.cohesion": ("liggghts", "cohesion/in.cohesion", same, bed_deck, printed_figures),
}


def host(name):
    return DECKS[name][0]


def fibre_text(name):
    with open(os.path.join(HERE, "in.%s.fibre" % name)) as f:
        return DECKS[name][3](f.read())


def native_text(name):
    root = EXAMPLES if host(name) == "lammps" else LIGGGHTS_EXAMPLES
    with open(os.path.join(root, DECKS[name][1])) as f:
        return DECKS[name][3](DECKS[name][2](f.read()))


def run_deck(lmp, text, workdir, tag, np=1, mpirun="mpirun", variables=None):
    """Runs one deck text; returns its log, parsed thermo, figures and wall seconds."""
    os.makedirs(workdir, exist_ok=True)
    deck, log = os.path.join(workdir, "in." + tag), os.path.join(workdir, "log." + tag)
    with open(deck, "w") as f:
        f.write(text)
    if os.path.exists(log):
        os.remove(log)
    cmd = mpi_prefix(mpirun, np) + [lmp, "-in", deck, "-log", log, "-echo", "none"]
    for k, v in (variables or {}).items():
        cmd += ["-var", k, str(v)]
    t0 = time.time()
    proc = subprocess.run(cmd, cwd=workdir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          env=lmp_env())
    seconds = time.time() - t0
    text = open(log).read() if os.path.exists(log) else ""
    out = proc.stdout.decode("utf-8", "replace")
    return {"rc": proc.returncode, "log": text, "output": out + text,
            "thermo": parse_thermo(text), "seconds": seconds}


def figures(name, run):
    return DECKS[name][4](run)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--lmp", default=os.path.join(HERE, "..", "..", "build", "fix", "lmp_fibre"))
    p.add_argument("--liggghts",
                   default=os.path.join(HERE, "..", "..", "build", "liggghts", "liggghts_fibre"))
    p.add_argument("--np", type=int, default=1)
    p.add_argument("--workdir", default="official-runs")
    p.add_argument("decks", nargs="*", default=sorted(DECKS))
    a = p.parse_args()
    for name in a.decks:
        lmp = os.path.abspath(a.lmp if host(name) == "lammps" else a.liggghts)
        wd = os.path.abspath(os.path.join(a.workdir, name))
        native = run_deck(lmp, native_text(name), wd, "native", a.np)
        fibre = run_deck(lmp, fibre_text(name), wd, "fibre", a.np)
        print("%s: native rc %d %.1f s, fix rc %d %.1f s (native/fix speed %.2fx)"
              % (name, native["rc"], native["seconds"], fibre["rc"], fibre["seconds"],
                 native["seconds"] / fibre["seconds"]))
        fn, ff = figures(name, native), figures(name, fibre)
        for key in fn:
            print("  %-6s native %-28s fix %s" % (key, fn[key], ff.get(key)))
        advice = re.search(r"could take a step of up to (\S+) .*?, (\S+) times", fibre["log"])
        if advice:
            print("  the log's step: up to %s (%s times the deck's)" % advice.groups())


if __name__ == "__main__":
    main()
