# shellcheck shell=bash
# Shared by the end-to-end scripts (e2e_speed.sh, mpi_scaling.sh); sourced, not run.
# shellcheck disable=SC2034  # the variables set here are the caller's

# The usage of the calling script: its head comment (the lines from 2 to the first line that
# is not a comment), without the '# '.
usage() {  # script
  awk 'NR == 1 { next } !/^#/ { exit } { sub(/^# ?/, ""); print }' "$1"
}

# The options of the end-to-end scripts, into the variables of the same name (the caller sets
# the defaults first): --deck, --N, --tend, --np, --lmp, --work, --extra, --mpirun-flags
# (mpirun_flags), --balance, --vars, --native; -h/--help prints the caller's usage and exits 0,
# anything else exits 2.
parse_options() {  # script "$@"
  local script=$1
  shift
  while [ $# -gt 0 ]; do
    case $1 in
      -h|--help) usage "$script"; exit 0 ;;
      --deck|--N|--tend|--np|--lmp|--work|--extra|--mpirun-flags|--balance|--vars|--native)
        [ $# -ge 2 ] || { echo "$(basename "$script"): $1 needs a value" >&2; exit 2; }
        case $1 in
          --deck) deck=$2 ;;
          --N) N=$2 ;;
          --tend) tend=$2 ;;
          --np) np=$2 ;;
          --lmp) lmp=$2 ;;
          --work) work=$2 ;;
          --extra) extra=$2 ;;
          --mpirun-flags) mpirun_flags=$2 ;;
          --balance) balance=$2 ;;
          --vars) vars=$2 ;;
          --native) native=$2 ;;
        esac
        shift 2 ;;
      *) echo "$(basename "$script"): unknown option $1 (--help: the usage)" >&2; exit 2 ;;
    esac
  done
}

# After parse_options: Open MPI allowed to run as root, one OpenMP thread, `cores`, the work
# directory made and entered with the deck prepared in it (prepare_fibre_deck), `timevar`
# (time_vars).
enter_work() {  # src
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
  cores=$(getconf _NPROCESSORS_ONLN)
  mkdir -p "$work"
  cd "$work" || exit 1
  prepare_fibre_deck "$1" "$deck"
  timevar=$(time_vars "$deck" "$tend")
}

# Copies examples/<deck>/ into the current directory (the examples stay untouched) with the
# thermo columns set to the fix's iterations, contacts and timings (f_fc[8] preconditioner
# setup, f_fc[9] linear solve, f_fc[15] Gauss-Seidel sweeps, seconds per step; f_fc[14] the
# sweeps' count), their running average over every step, and a closing line
# "fibre_timing setup_per_step S solve_per_step S sweep_per_step S sweeps_per_step N".
prepare_fibre_deck() {  # src deck
  local src=$1 deck=$2
  cp "$src/examples/$deck/"*."$deck" "$src/examples/$deck/in.$deck.native" .
  sed -i 's/^variable  *fibre_thermo string .*/variable  fibre_thermo string "f_fc[1] f_fc[3] f_fc[8] f_fc[9] f_fc[15]"/' "in.$deck"
  sed -i "s/^include  *run\.$deck/fix       fc_time all ave\/time 1 1 1 f_fc[8] f_fc[9] f_fc[15] f_fc[14] ave running\n&/" "in.$deck"
  echo 'print "fibre_timing setup_per_step $(f_fc_time[1]) solve_per_step $(f_fc_time[2]) sweep_per_step $(f_fc_time[3]) sweeps_per_step $(f_fc_time[4])"' >> "in.$deck"
}

# The deck variables that run it for `tend` simulated seconds (the silo: the fill only).
time_vars() {  # deck tend
  case $1 in
    material) echo "-var tend $2" ;;
    silo) echo "-var tfill $2 -var tflow 0" ;;
    *) echo "" ;;
  esac
}
