// lmp_fibre: the LAMMPS executable with fibre_contact's styles registered.
//
// It takes the same command-line flags as `lmp` (LAMMPS parses them) and runs every stock
// style of the linked LAMMPS library; the only difference is that `fix fibre_contact` is
// known before the input is read.
#include <mpi.h>

#include <string>

#include "fix_fibre_contact.h"
#include "input.h"
#include "lammps.h"
#include "modify.h"
#include "universe.h"
#include "utils.h"

using namespace LAMMPS_NS;

namespace {
template <typename T> Fix *fix_creator(LAMMPS *lmp, int narg, char **arg)
{
  return new T(lmp, narg, arg);
}
} // namespace

int main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  {
    LAMMPS lmp(argc, argv, MPI_COMM_WORLD);
    (*lmp.modify->fix_map)["fibre_contact"] = &fix_creator<FixFibreContact>;
    utils::logmesg(&lmp,
                   std::string("fibre_contact add-on ") + FIBRE_VERSION +
                       ": fix fibre_contact (nonsmooth contact dynamics, fibre preconditioner)\n");
    lmp.input->file();
  }
  MPI_Finalize();
  return 0;
}
