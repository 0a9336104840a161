#!/usr/bin/env python3
"""The official LAMMPS granular decks beside their fix fibre_contact conversions.

Each native deck is read from Debian's lammps-examples (/usr/share/lammps/examples) or
liggghts-doc (LIGGGHTS's public tutorials); its conversion is in.NAME.fibre beside this
script (every changed line marked "fibre:"). Both twins run with lmp_fibre (lmp plus the fix)
or liggghts_fibre (liggghts plus the fix), one at a time, and the script prints each deck's
figure, native against fix, with the wall seconds.

  python3 examples/official/official.py [--lmp build/fix/lmp_fibre] [--np 1] [--workdir W]
      [--keywords "contact_every auto"] [DECK ...]
"""

import argparse
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools"))
from lammps_runs import least_squares_slope, lmp_env, mpi_prefix, parse_thermo  # noqa: E402

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


def funnel_deck(text):
    """granregion.funnel for both twins: its step printed (the deck computes it from the
    collision time)."""
    old = "timestep\t${dt}"
    assert old in text
    return text.replace(old, old + '\nprint "FUNNEL_STEP ${dt}"', 1)


def funnel_figures(run):
    """granregion.funnel: grains after the fill and after settling on the plug (none lost),
    and in the discharge (the third run, the plug removed, grains leaving through the
    bottom's open boundary) the grains discharged by the end and the mean flow rate from the
    first grain's leaving until 60% have left (grains per time unit, fitted)."""
    blocks = run["thermo"]
    if len(blocks) < 3:
        return {}
    out = {"filled": blocks[0][-1]["Atoms"], "settled": blocks[1][-1]["Atoms"],
           "left": blocks[2][-1]["Atoms"]}
    n0 = blocks[2][0]["Atoms"]
    out["discharged"] = n0 - out["left"]
    window = [r for r in blocks[2] if 0.4 * n0 <= r["Atoms"] < n0]
    step = re.search(r"^FUNNEL_STEP (\S+)", run["log"], re.M)
    if len(window) >= 3 and step:
        # the least-squares slope of the grains left against time over the window
        t = [r["Step"] * float(step.group(1)) for r in window]
        n = [r["Atoms"] for r in window]
        out["rate"] = -least_squares_slope(t, n)
    return out


# The LIGGGHTS tutorials and LAMMPS's funnel shortened for the tests: each (old, new) replaces old's first
# occurrence, in order, in both twins' text (after their DECKS edits)
SHORTER = {
    # three of the four insertions: 900 grains falling
    "insert_stream": (("run\t\t100000", "run 60000"),),
    # the same growth to the same solid fraction in a fifth of the steps
    "packing": (("growts equal 50000", "growts equal 10000"),
                ("relaxts equal 20000", "relaxts equal 4000")),
    # the first 310 grains, 120 of them carried past the belt's end
    "conveyor": (("run\t\t\t140000 upto", "run 80000 upto"),),
    # 200 grains down the chute, to rest
    "meshGran": (("run\t\t\t10000 upto", "run 4000 upto"),
                 ("run\t\t\t40000 upto", "run 30000 upto")),
    # one insertion, the bucket made a wall, moved and turned for a moment
    "movingMeshGran": (("run\t\t8000 upto", "run 2000 upto"), ("run 14999 upto", "run 5999 upto"),
                       ("run 15000 upto", "run 6000 upto"), ("run\t\t15000", "run 1000"),
                       ("run 15000", "run 1000")),
    # 510 grains on the chute, before any reaches its end
    "chute_wear": (("run    100000 upto", "run 40000 upto"),),
    # the mixer: 400 grains, half the pour, 80000 steps of mixing (the blades turn 72 degrees)
    "granregion.mixer": (("pour 1000 1 42424", "pour 400 1 42424"), ("run\t\t200000 ", "run 100000"),
                         ("run\t\t200000", "run 80000")),
    # LAMMPS's funnel: 400 grains at four times the step (0.03 collision times, as native
    # keeps the deck's physics there), landed on the plug, then 10.5 time units of discharge
    "granregion.funnel": (("dt equal ${tcol}*0.05", "dt equal ${tcol}*0.2"),
                          ("logfreq equal 1000", "logfreq equal 250"),
                          ("pour 2000 1 42424", "pour 400 1 42424"),
                          ("run\t\t20000 ", "run 5000"), ("run\t\t150000", "run 20000"),
                          ("run\t\t100000", "run 25000")),
}


def shortened(name, text):
    """The deck with fewer steps, for the tests (pour: 10000 steps of insertion, 8000 of flow,
    thermo every 500; the LIGGGHTS tutorials: SHORTER)."""
    for old, new in SHORTER.get(name, ()):
        assert old in text, (name, old)
        text = text.replace(old, new, 1)
    if name != "pour":
        return text
    first = text.index("run\t\t25000")
    text = text[:first] + "run 10000" + text[first + len("run\t\t25000"):]
    text = text.replace("run\t\t25000", "run 8000").replace("thermo\t\t1000", "thermo 500")
    return text


def with_drum_figures(text):
    return text + DRUM_FIGURES


def intended_drum_deck(text):
    """pour.drum as its comments intend, in both twins: the drum's curved wall without its top
    cap (`open 2`: the deck adds its own top plane for the second run), so that no grain poured
    from above enters the drum through a wall; and its delete_atoms acting on the grains above
    half the drum's height (the dynamic group it names is evaluated every 10000 steps, so at
    step 2000 it is still the empty group of step 0, and deletes nothing). As shipped, each
    grain that falls into the drum through its cap is inside a wall by most of its radius, and
    native's wall/gran/region pushes it out downwards, at twice its speed (24 to 54 m/s)."""
    old_cap = "side in rotate v_theta ${xc} ${yc} 0 0 0 1\nregion          bottom_wall"
    old_group = "group           delgroup dynamic all var zmax every 10000"
    assert old_cap in text and old_group in text
    text = text.replace(old_cap, old_cap.replace("side in", "side in open 2"))
    return with_drum_figures(text.replace(old_group, old_group.replace("10000", "1")))


def same(text):
    return text


def with_figures(text):
    return text + FLATWALL_FIGURES


def without_dumps(text):
    """The deck without its dumps (VTK, mesh STL and mesh VTK files)."""
    return re.sub(r"(?m)^dump\s.*$", "", text)


def bed_deck(text):
    """The cohesion tutorial without its VTK dump, with the bed's figure."""
    return without_dumps(text) + BED_FIGURES


# The other LIGGGHTS tutorials' figures, printed at the deck's end (both twins; the inserted
# count is the insertion fix's own log line): the stream's are the cohesion bed's
STREAM_FIGURES = BED_FIGURES

# packing: the solid fraction of the grown grains in the 0.1 x 0.1 x 0.15 box, and the mean
# number of grains each touches (overlapping neighbours: the compliance's overlaps)
PACKING_FIGURES = """
variable na equal count(all)
compute pk_r all property/atom radius
variable pk_v atom 4.0/3.0*PI*c_pk_r^3
compute pk_vsum all reduce sum v_pk_v
variable phi equal c_pk_vsum/(0.1*0.1*0.15)
compute pk_cn all contact/atom
compute pk_cnsum all reduce sum c_pk_cn
variable cn equal c_pk_cnsum/count(all)
variable zc equal xcm(all,z)
thermo_style custom step atoms v_phi v_cn
run 0
print "FIGURES atoms ${na} phi ${phi} cn ${cn} zc ${zc}"
"""

# conveyor: the grains past the belt's end (x < -0.1, dropped into the box) and any outside
# the box mesh
CONVEYOR_FIGURES = """
variable na equal count(all)
region cv_off block INF -0.1 INF INF INF INF units box
region cv_box block -0.5 0.5 -0.2 0.2 -0.2 INF units box
variable off equal count(all,cv_off)
variable outside equal count(all)-count(all,cv_box)
variable xc equal xcm(all,x)
print "FIGURES atoms ${na} off ${off} outside ${outside} xc ${xc}"
"""

# meshGran: where the grains come to rest at the bottom of the chute (the bed's centre: x,
# and the height above the floor at z = -1.2) and any outside the mesh's bounding box
CHUTE_FIGURES = """
variable na equal count(all)
region mg_box block -0.008 0.508 -0.058 0.008 -1.209 0.008 units box
variable outside equal count(all)-count(all,mg_box)
variable xc equal xcm(all,x)
variable zc equal xcm(all,z)+1.2
print "FIGURES atoms ${na} outside ${outside} xc ${xc} zc ${zc}"
"""

# movingMeshGran: the grains the bucket holds up out of the bed (centres above z = 0; the
# settled bed's top is at about -0.21), and the grains' centre height
BUCKET_FIGURES = """
variable na equal count(all)
region mm_up block INF INF INF INF 0.0 INF units box
variable lifted equal count(all,mm_up)
variable zc equal xcm(all,z)
print "FIGURES atoms ${na} lifted ${lifted} zc ${zc}"
"""


def bucket_deck(text):
    """movingMeshGran for both twins, shortened (the whole deck took the fix 17 minutes): the
    bed settles until step 15000, not 30000, before the bucket becomes a wall, and the bucket
    turns for 15000 steps, not 25000 (135 degrees: to the top of its turn, its load held up);
    no dumps, its figures printed."""
    for old, new in (("run\t\t29999 upto", "run 14999 upto"),
                     ("run\t\t30000 upto", "run 15000 upto"), ("run\t\t\t25000", "run 15000")):
        assert old in text
        text = text.replace(old, new)
    return without_dumps(text) + BUCKET_FIGURES


WEAR_FIGURES = """
variable na equal count(all)
print "FIGURES atoms ${na}"
"""


def tutorial_deck(figures_text):
    """A LIGGGHTS tutorial's edit for both twins: no dumps, its figures printed at the end."""
    return lambda text: without_dumps(text) + figures_text


def inserted(run):
    """The grains the deck's insertion fixes put in (their log's last running total)."""
    totals = re.findall(r"a total of (\d+) particle templates", run["log"])
    return float(totals[-1]) if totals else float("nan")


def window_mean(run, block, key, first=0.0, last=1.0):
    """The mean of a thermo column over the fraction [first, last) of the rows of run block
    `block` (negative: from the end)."""
    blocks = run["thermo"]
    if not -len(blocks) <= block < len(blocks):
        return float("nan")
    rows = blocks[block]
    lo = int(first * len(rows))
    rows = rows[lo:max(int(last * len(rows)), lo + 1)]
    return sum(r[key] for r in rows) / len(rows) if rows else float("nan")


def stream_figures(run):
    """insert_stream: grains inserted and kept, and the falling stream's kinetic energy at the
    end (the box has no walls: grains meet only each other) and centre height."""
    out = printed_figures(run)
    out["inserted"] = inserted(run)
    out["ke"] = window_mean(run, -1, "KinEng", 0.999)
    return out


def packing_figures(run):
    """packing: grains kept; the grown packing's solid fraction and mean contacts per grain."""
    out = printed_figures(run)
    out["inserted"] = inserted(run)
    return out


def conveyor_figures(run):
    """conveyor: grains inserted and kept, those past the belt's end at the end; the mean
    kinetic energy of the run (the belt carries the stream off the feed)."""
    out = printed_figures(run)
    out["inserted"] = inserted(run)
    out["ke"] = window_mean(run, -1, "KinEng")
    return out


def meshgran_figures(run):
    """meshGran: grains inserted and kept, the mean kinetic energy of the flow down the chute
    (the first half of the run after insertion) and where the grains come to rest."""
    out = printed_figures(run)
    out["inserted"] = inserted(run)
    out["ke"] = window_mean(run, 1, "KinEng", 0.0, 0.5)
    return out


def bucket_figures(run):
    """movingMeshGran: grains inserted and kept; the kinetic energy while the bucket lifts
    (the last run) and the grains it holds up at the end."""
    out = printed_figures(run)
    out["inserted"] = inserted(run)
    out["ke"] = window_mean(run, -1, "KinEng")
    return out


def wear_figures(run):
    """chute_wear: the grains discharged (inserted, less those still in the domain: its
    boundary is f f f, so grains that leave the chute leave the run), and the mean kinetic
    energy of the run."""
    out = printed_figures(run)
    out["inserted"] = inserted(run)
    out["ke"] = window_mean(run, -1, "KinEng")
    out["discharged"] = out["inserted"] - out.get("atoms", float("nan"))
    return out


# name: (host, native path, the native twin's edit, both twins' edit, figures)
DECKS = {
    "granregion.box": ("lammps", "granregion/in.granregion.box", box_deck, same, box_figures),
    "pour.flatwall": ("lammps", "granular/in.pour.flatwall", same, with_figures,
                      printed_figures),
    "granregion.mixer": ("lammps", "granregion/in.granregion.mixer", same, mixer_deck,
                         mixer_figures),
    "pour.drum": ("lammps", "granular/in.pour.drum", same, with_drum_figures,
                  printed_figures),
    "pour.drum.intended": ("lammps", "granular/in.pour.drum", same, intended_drum_deck,
                           printed_figures),
    "pour": ("lammps", "pour/in.pour", same, same, pour_figures),
    "granregion.funnel": ("lammps", "granregion/in.granregion.funnel", same, funnel_deck,
                          funnel_figures),
    "cohesion.noCohesion": ("liggghts", "cohesion/in.noCohesion", same, bed_deck,
                            printed_figures),
    "cohesion.cohesion": ("liggghts", "cohesion/in.cohesion", same, bed_deck, printed_figures),
    "insert_stream": ("liggghts", "insert_stream/in.insert_stream", same,
                      tutorial_deck(STREAM_FIGURES), stream_figures),
    "packing": ("liggghts", "packing/in.packing", same, tutorial_deck(PACKING_FIGURES),
                packing_figures),
    "conveyor": ("liggghts", "conveyor/in.conveyor", same, tutorial_deck(CONVEYOR_FIGURES),
                 conveyor_figures),
    "meshGran": ("liggghts", "meshGran/in.meshGran", same, tutorial_deck(CHUTE_FIGURES),
                 meshgran_figures),
    "movingMeshGran": ("liggghts", "movingMeshGran/in.movingMeshGran", same, bucket_deck,
                       bucket_figures),
    "chute_wear": ("liggghts", "chute_wear/in.chute_wear", same, tutorial_deck(WEAR_FIGURES),
                   wear_figures),
}


# decks that are another deck's conversion with other edits
CONVERSIONS = {"pour.drum.intended": "pour.drum"}


def host(name):
    return DECKS[name][0]


def with_keywords(text, keywords):
    """The deck with `keywords` added to each fix fibre_contact command (after its last
    continued line)."""
    lines, out, i = text.split("\n"), [], 0
    while i < len(lines):
        line = lines[i]
        if not re.match(r"\s*fix\s+\S+\s+\S+\s+fibre_contact\b", line):
            out.append(line)
            i += 1
            continue
        while line.rstrip().endswith("&") and i + 1 < len(lines):
            out.append(line)
            i += 1
            line = lines[i]
        out.append(line.rstrip() + " " + keywords)
        i += 1
    return "\n".join(out)


def fibre_text(name, keywords=""):
    """The conversion of deck `name`, with `keywords` added to its fix fibre_contact commands
    (for example 'contact_every auto')."""
    with open(os.path.join(HERE, "in.%s.fibre" % CONVERSIONS.get(name, name))) as f:
        text = DECKS[name][3](f.read())
    return with_keywords(text, keywords) if keywords else text


def native_path(name):
    root = EXAMPLES if host(name) == "lammps" else LIGGGHTS_EXAMPLES
    return os.path.join(root, DECKS[name][1])


def native_text(name):
    with open(native_path(name)) as f:
        return DECKS[name][3](DECKS[name][2](f.read()))


def inputs(name):
    """The folder of the deck's original: the files it reads (a tutorial's meshes/) are there."""
    return os.path.dirname(native_path(name))


def run_deck(lmp, text, workdir, tag, np=1, mpirun="mpirun", variables=None, source=None):
    """Runs one deck text; returns its log, parsed thermo, figures and wall seconds. With
    source (a folder: inputs(name)), its meshes/ is linked into workdir and post/ made there,
    as a LIGGGHTS tutorial reads and writes them."""
    os.makedirs(workdir, exist_ok=True)
    if source:
        os.makedirs(os.path.join(workdir, "post"), exist_ok=True)
        meshes, link = os.path.join(source, "meshes"), os.path.join(workdir, "meshes")
        if os.path.isdir(meshes) and not os.path.lexists(link):
            os.symlink(meshes, link)
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
    text = open(log, errors="replace").read() if os.path.exists(log) else ""
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
    p.add_argument("--keywords", default="",
                   help="added to the conversions' fix fibre_contact, e.g. 'contact_every auto'")
    p.add_argument("decks", nargs="*", default=sorted(DECKS))
    a = p.parse_args()
    for name in a.decks:
        lmp = os.path.abspath(a.lmp if host(name) == "lammps" else a.liggghts)
        wd = os.path.abspath(os.path.join(a.workdir, name))
        src = inputs(name) if host(name) == "liggghts" else None
        native = run_deck(lmp, native_text(name), wd, "native", a.np, source=src)
        fibre = run_deck(lmp, fibre_text(name, a.keywords), wd, "fibre", a.np, source=src)
        print("%s: native rc %d %.1f s, fix rc %d %.1f s (native/fix speed %.2fx)"
              % (name, native["rc"], native["seconds"], fibre["rc"], fibre["seconds"],
                 native["seconds"] / fibre["seconds"]))
        fn, ff = figures(name, native), figures(name, fibre)
        for key in fn:
            print("  %-6s native %-28s fix %s" % (key, fn[key], ff.get(key)))
        advice = re.search(r"could take a step of up to ([^,\s]+), (\S+) times", fibre["log"])
        if advice:
            print("  the log's step: up to %s (%s times the deck's)" % advice.groups())


if __name__ == "__main__":
    main()
