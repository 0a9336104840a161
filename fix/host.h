// The host program this front end is compiled against: LAMMPS 29 Sep 2021 (lmp_fibre) or, with
// FIBRE_HOST_LIGGGHTS defined, LIGGGHTS 3.8 (liggghts_fibre). Both descend from the same LAMMPS
// and share the Fix interface almost whole; what differs is kept here, so that the fix, its
// detection, output and exchange are one source for both (doc/design.md section 5).
//
// - Messages: LIGGGHTS's Error takes const char * only and it has no utils::logmesg, so the
//   front end formats its messages as std::string and passes them through these functions.
// - Halo communication: comm->forward_comm_fix(fix, n) in LAMMPS, (fix) in LIGGGHTS (the
//   fix's comm_forward decides); the macros fibre_forward_comm/fibre_reverse_comm come from the
//   force-included compat header of each host (lammps_compat.h, liggghts/liggghts_compat.h).
//   pack_*_comm return the number of values in LAMMPS, the values per atom in LIGGGHTS.
// - Atom callbacks: Atom::GROW/RESTART in LAMMPS, the numbers 0/1 in LIGGGHTS.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

#include "atom.h"
#include "error.h"
#include "force.h"
#include "pair.h"
#include "lammps.h"

namespace fibre_lmp {

// A message as the host's Error takes it: LAMMPS's const char * overloads are fmt templates
// (whose back end Debian's library lacks), so it gets the std::string one.
#ifdef FIBRE_HOST_LIGGGHTS
inline constexpr int kGrowCallback = 0, kRestartCallback = 1;
inline constexpr const char *kHostName = "LIGGGHTS";
inline const char *host_text(const std::string &message)
{
  return message.c_str();
}
#else
inline constexpr int kGrowCallback = LAMMPS_NS::Atom::GROW;
inline constexpr int kRestartCallback = LAMMPS_NS::Atom::RESTART;
inline constexpr const char *kHostName = "LAMMPS";
inline const std::string &host_text(const std::string &message)
{
  return message;
}
#endif

// What a fix's pack_*_comm returns: the values packed in LAMMPS, the values per atom in
// LIGGGHTS (its Comm multiplies by the number of atoms).
inline int packed_count(int total, int per_atom)
{
#ifdef FIBRE_HOST_LIGGGHTS
  (void)total;
  return per_atom;
#else
  (void)per_atom;
  return total;
#endif
}

// Error->all: every process stops with the message.
[[noreturn]] inline void fail(LAMMPS_NS::Error *error, const char *file, int line,
                              const std::string &message)
{
  error->all(file, line, host_text(message));
  std::exit(1); // not reached: Error::all ends the run
}

// Error->one: this process alone found the error.
[[noreturn]] inline void fail_one(LAMMPS_NS::Error *error, const char *file, int line,
                                  const std::string &message)
{
  error->one(file, line, host_text(message));
  std::exit(1);
}

inline void warn(LAMMPS_NS::Error *error, const char *file, int line, const std::string &message)
{
  error->warning(file, line, host_text(message));
}

// A line for the screen and the log file (processes without them print nothing).
inline void logmesg(LAMMPS_NS::LAMMPS *lmp, const std::string &message)
{
  if (lmp->screen) std::fputs(message.c_str(), lmp->screen);
  if (lmp->logfile) std::fputs(message.c_str(), lmp->logfile);
}

// The start of a style name ("gran" of "gran/hooke/history").
inline bool starts_with(const char *text, const char *prefix)
{
  return text && std::string(text).rfind(prefix, 0) == 0;
}

// The granular pair style whose neighbour list is the contact graph and whose coefficients are
// the material: the pair style itself (gran/* or granular), or the one granular sub-style of
// pair_style hybrid or hybrid/overlay. nullptr if there is none; style: its name.
inline LAMMPS_NS::Pair *granular_pair(LAMMPS_NS::LAMMPS *lmp, std::string &style)
{
  LAMMPS_NS::Force *force = lmp->force;
  style = force->pair_style ? force->pair_style : "";
  if (!force->pair) return nullptr;
  if (starts_with(style.c_str(), "gran")) return force->pair;
  if (!starts_with(style.c_str(), "hybrid")) return nullptr;
  for (const char *name : {"granular", "gran/hertz/history", "gran/hooke/history", "gran/hooke"})
    if (LAMMPS_NS::Pair *sub = force->pair_match(name, 1)) {
      style = name;
      return sub;
    }
  return nullptr;
}

} // namespace fibre_lmp
