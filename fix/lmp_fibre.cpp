// lmp_fibre: the LAMMPS executable with fibre_contact's styles registered.
//
// It takes the same command-line flags as `lmp` (LAMMPS parses them) and runs every stock
// style of the linked LAMMPS library; the only difference is that `fix fibre_contact` is
// known before the input is read.
#include "host_main.h"
#include "modify.h"

int main(int argc, char **argv)
{
  return fibre_lmp::host_main(
      argc, argv, [](LAMMPS_NS::LAMMPS &lmp, const char *name, LAMMPS_NS::Modify::FixCreator f) {
        (*lmp.modify->fix_map)[name] = f;
      });
}
