"""The LIGGGHTS scenes of examples/liggghts with fix fibre_contact, small and short, against
their native twins and on 2 processes.

- Hopper (STL mesh, 600 spheres): the fibre twin, serial and mpirun -np 2, and the native
  twin discharge; no sphere ever passes through the mesh (v_nesc = 0 on every thermo line);
  the discharge rate of the fibre twin is within 10% of the native twin's (a 600-sphere hopper
  fluctuates by a few per cent between packings; the 2500-sphere figures are in
  examples/liggghts/README.md), and np 2 within 10% of serial (parallel insertion packs
  differently).
- Mixer (STL drum and a blade turned by fix move/mesh, 1200 spheres, half a revolution): no
  sphere is lost or leaves the drum, serial and np 2; the blade's torque from the fix's wall
  loads (f_ID[2][6]) opposes its rotation.
"""

import os
import shutil
import subprocess
import sys

import fibre_e2e as e2e

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..",
                                "examples", "liggghts"))
import compare  # noqa: E402


def scene_dir(args, name):
    """A copy of examples/liggghts/NAME with its meshes, in the work directory."""
    src = os.path.join(args.source, "examples", "liggghts", name)
    dst = os.path.join(args.workdir, name)
    if os.path.exists(dst):
        shutil.rmtree(dst)
    shutil.copytree(src, dst)
    subprocess.run([sys.executable, os.path.join(dst, "make_mesh.py"), "--out",
                    os.path.join(dst, "meshes")], check=True, stdout=subprocess.DEVNULL)
    return dst


def run_deck(args, exe, workdir, deck, log, np=1, variables=None):
    cmd = e2e.mpi_prefix(args.mpirun, np) + [exe, "-in", deck, "-log", log, "-echo", "none"]
    for key, value in (variables or {}).items():
        cmd += ["-var", key, str(value)]
    proc = subprocess.run(cmd, cwd=workdir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          env=e2e.lmp_env(), timeout=1200)
    return proc.returncode, proc.stdout.decode("utf-8", "replace")


def failure(rc, out):
    return "rc %d" % rc + ("" if rc == 0 else ", " + out[-300:])


def native_liggghts():
    for path in ("/usr/bin/liggghts", shutil.which("liggghts") or ""):
        if path and os.path.exists(path):
            return path
    return None


def hopper(args, checks):
    workdir = scene_dir(args, "hopper")
    small = {"N": 600, "tfill": 0.3, "tdis": 0.8}
    runs = [("fibre np 1", args.lmp, "in.hopper.fibre", 1),
            ("fibre np 2", args.lmp, "in.hopper.fibre", 2)]
    native = native_liggghts()
    if native:
        runs.append(("native", native, "in.hopper.native", 1))
    rates = {}
    for name, exe, deck, np in runs:
        log = os.path.join(workdir, "log." + name.replace(" ", "_"))
        rc, out = run_deck(args, exe, workdir, deck, log, np, small)
        if not checks.check(rc == 0, "hopper %s completes" % name, failure(rc, out)):
            continue
        blocks, _ = compare.parse(log)
        escaped = max(compare.joined(blocks, "nesc"))
        checks.check(escaped == 0, "hopper %s: no sphere through the mesh" % name,
                     "largest v_nesc %g" % escaped)
        fit = compare.hopper(log, 0.2, 0.8)
        rates[name] = fit["rate_n"]
        checks.check(fit["left"] < 0.05 * small["N"], "hopper %s discharges" % name,
                     "%d spheres left, rate %.0f/s" % (fit["left"], fit["rate_n"]))
    if "fibre np 1" in rates and "native" in rates:
        checks.agree(rates["fibre np 1"], rates["native"], 0.10,
                     "hopper: discharge rate of the fibre twin within 10% of native's", "%.0f")
    if "fibre np 1" in rates and "fibre np 2" in rates:
        checks.agree(rates["fibre np 2"], rates["fibre np 1"], 0.10,
                     "hopper: np 2 discharges as serial", "%.0f")


def mixer(args, checks):
    workdir = scene_dir(args, "mixer")
    for np in (1, 2):
        log = os.path.join(workdir, "log.np%d" % np)
        rc, out = run_deck(args, args.lmp, workdir, "in.mixer.fibre", log, np,
                           {"revs": 0.5, "tsettle": 0.3})
        if not checks.check(rc == 0, "mixer np %d completes" % np, failure(rc, out)):
            continue
        figures = compare.mixer(log)
        checks.check(figures["atoms_min"] == 1200 and figures["nout_max"] == 0,
                     "mixer np %d: no sphere lost or out of the drum (moving blade mesh)" % np,
                     "atoms %d..%d, outside %d" % (figures["atoms_min"], figures["atoms_max"],
                                                   figures["nout_max"]))
        checks.check(figures["tz"] < 0, "mixer np %d: the blade's torque opposes its rotation"
                     % np, "mean tz %.4g N m" % figures["tz"])


def main():
    args = e2e.parse_args()
    checks = e2e.Checks("LIGGGHTS scenes: hopper and mixer with STL meshes")
    hopper(args, checks)
    mixer(args, checks)
    checks.close()


if __name__ == "__main__":
    main()
