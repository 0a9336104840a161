# Shared by the end-to-end scripts (e2e_speed.sh, mpi_scaling.sh); sourced, not run.

# Copies examples/<deck>/ into the current directory (the examples stay untouched) with the
# thermo columns set to the fix's iterations, contacts and timings (f_fc[8] preconditioner
# setup, f_fc[9] linear solve, f_fc[15] Gauss-Seidel sweeps, seconds per step), their running
# average over every step, and a closing line
# "fibre_timing setup_per_step S solve_per_step S sweep_per_step S".
prepare_fibre_deck() {  # src deck
  local src=$1 deck=$2
  cp "$src/examples/$deck/"*."$deck" "$src/examples/$deck/in.$deck.native" .
  sed -i 's/^variable  *fibre_thermo string .*/variable  fibre_thermo string "f_fc[1] f_fc[3] f_fc[8] f_fc[9] f_fc[15]"/' "in.$deck"
  sed -i "s/^include  *run\.$deck/fix       fc_time all ave\/time 1 1 1 f_fc[8] f_fc[9] f_fc[15] ave running\n&/" "in.$deck"
  echo 'print "fibre_timing setup_per_step $(f_fc_time[1]) solve_per_step $(f_fc_time[2]) sweep_per_step $(f_fc_time[3])"' >> "in.$deck"
}

# The deck variables that run it for `tend` simulated seconds (the silo: the fill only).
time_vars() {  # deck tend
  case $1 in
    material) echo "-var tend $2" ;;
    silo) echo "-var tfill $2 -var tflow 0" ;;
    *) echo "" ;;
  esac
}
