// liggghts_fibre: the LIGGGHTS executable with fix fibre_contact registered, a drop-in for
// `liggghts` (same command-line flags, every stock style of the linked libliggghts).
//
// LIGGGHTS 3.8 keeps Modify::fix_map private and has no plugin loader. An explicit template
// instantiation may name a private member ([temp.explicit]: access is not checked in its
// arguments), so MemberPointer below hands out &Modify::fix_map.
#include <map>
#include <string>

#include "host_main.h"
#include "modify.h"

namespace {

using FixCreator = LAMMPS_NS::Fix *(*)(LAMMPS_NS::LAMMPS *, int, char **);
using FixMap = std::map<std::string, FixCreator>;

struct FixMapTag {
  using type = FixMap *LAMMPS_NS::Modify::*;
  friend type member(FixMapTag);
};

template <typename Tag, typename Tag::type Member> struct MemberPointer {
  friend typename Tag::type member(Tag) { return Member; }
};
template struct MemberPointer<FixMapTag, &LAMMPS_NS::Modify::fix_map>;

} // namespace

int main(int argc, char **argv)
{
  return fibre_lmp::host_main(argc, argv,
                              [](LAMMPS_NS::LAMMPS &lmp, const char *name, FixCreator f) {
                                (*(lmp.modify->*member(FixMapTag{})))[name] = f;
                              });
}
