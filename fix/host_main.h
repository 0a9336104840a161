// The main() of a host executable (lmp_fibre, liggghts_fibre): the host's own command line,
// this project's styles registered before any input is read, then the input.
#pragma once

#include <mpi.h>

#include <string>

#include "fix_fibre_contact.h"
#include "host.h"
#include "input.h"
#include "lammps.h"
#include "universe.h"

namespace fibre_lmp {

template <typename T> LAMMPS_NS::Fix *fix_creator(LAMMPS_NS::LAMMPS *lmp, int narg, char **arg)
{
  return new T(lmp, narg, arg);
}

// register_fix(lmp, name, creator) enters a fix style in the host's table.
template <typename RegisterFix> int host_main(int argc, char **argv, RegisterFix register_fix)
{
  MPI_Init(&argc, &argv);
  {
    LAMMPS_NS::LAMMPS lmp(argc, argv, MPI_COMM_WORLD);
    register_fix(lmp, "fibre_contact", &fix_creator<LAMMPS_NS::FixFibreContact>);
    if (lmp.universe->me == 0)
      logmesg(&lmp, std::string("fibre_contact add-on ") + FIBRE_VERSION +
                        ": fix fibre_contact (nonsmooth contact dynamics, fibre preconditioner), " +
                        kHostName + " front end\n");
    lmp.input->file();
  }
  MPI_Finalize();
  return 0;
}

} // namespace fibre_lmp
