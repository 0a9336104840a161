#!/usr/bin/env bash
# Installs every package fibre_contact needs from Debian's archive (bookworm).
# Idempotent: when all packages are present it installs nothing and touches no network.
set -euo pipefail

packages=(
  # build tools
  cmake g++ make pkg-config clang libclang-rt-14-dev clang-format
  # LAMMPS with headers, cmake config and official example decks
  lammps liblammps-dev lammps-examples
  # LIGGGHTS with headers and its tutorial decks (the LIGGGHTS front end)
  liggghts libliggghts-dev liggghts-doc
  # MPI, linear algebra, direct solver
  openmpi-bin libopenmpi-dev libeigen3-dev libmumps-dev
  # formatting (LAMMPS headers need fmt, Debian omits the bundled copy)
  libfmt-dev
  # tests and benchmarks
  googletest libgtest-dev libgmock-dev libbenchmark-dev
  # analysis and plotting scripts
  python3 python3-numpy python3-matplotlib
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
