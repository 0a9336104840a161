// liggghts_fibre: the LIGGGHTS executable with fix fibre_contact registered, a drop-in for
// `liggghts` (same command-line flags, every stock style of the linked libliggghts).
//
// LIGGGHTS 3.8 keeps Modify::fix_map private and has no plugin loader. An explicit template
// instantiation may name a private member ([temp.explicit]: access is not checked in its
// arguments), so MemberPointer below hands out &Modify::fix_map once, before input is read.
#include <mpi.h>

#include <map>
#include <string>

#include "fix_fibre_contact.h"
#include "host.h"
#include "input.h"
#include "lammps.h"
#include "modify.h"
#include "universe.h"

using namespace LAMMPS_NS;

namespace {

using FixCreator = Fix *(*)(LAMMPS *, int, char **);
using FixMap = std::map<std::string, FixCreator>;

struct FixMapTag {
  using type = FixMap *Modify::*;
  friend type member(FixMapTag);
};

template <typename Tag, typename Tag::type Member> struct MemberPointer {
  friend typename Tag::type member(Tag) { return Member; }
};
template struct MemberPointer<FixMapTag, &Modify::fix_map>;

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
    FixMap &fixes = *(lmp.modify->*member(FixMapTag{}));
    fixes["fibre_contact"] = &fix_creator<FixFibreContact>;
    if (lmp.universe->me == 0)
      fibre_lmp::logmesg(&lmp, std::string("fibre_contact add-on ") + FIBRE_VERSION +
                                   ": fix fibre_contact (nonsmooth contact dynamics, fibre "
                                   "preconditioner), LIGGGHTS front end\n");
    lmp.input->file();
  }
  MPI_Finalize();
  return 0;
}
