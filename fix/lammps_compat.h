// Compatibility layer between this project and Debian's LAMMPS 29 Sep 2021 headers.
//
// 1. fmt: Debian's liblammps-dev omits the fmt headers that LAMMPS bundles, and the system
//    libfmt-dev (9.x) no longer has fmt::make_args_checked, which the templates in utils.h
//    and error.h name. This header is force-included before any LAMMPS header and declares a
//    replacement, so the headers parse. Our code calls only the std::string overloads of
//    error->all/one/warning and utils::logmesg and formats its messages itself.
// 2. Communication: LAMMPS 2022 and later renamed comm->forward_comm_fix(this) to
//    comm->forward_comm(this). Our code calls the fibre_forward_comm/fibre_reverse_comm
//    wrappers below, so only this file changes for a newer LAMMPS. The reverse comm is the
//    variable-size one (reverse_comm_variable in LAMMPS 2022): with `newton off`, as granular
//    decks have it, Comm::init sizes no buffer for a fix's reverse comm (maxreverse = 0), and
//    the fixed-size call overflowed the receive buffer on a process that sends more ghosts than
//    it receives (the silo at N 5000 on two processes). The variable one asks the fix for its
//    size (pack_reverse_comm_size) and grows both buffers.
#pragma once

#ifdef __cplusplus
#include <fmt/format.h>

namespace fmt {
template <typename... Args, typename S>
inline auto make_args_checked(const S &, const Args &...args)
{
  return fmt::make_format_args(args...);
}
} // namespace fmt

#define FIBRE_LAMMPS_COMM_FIX_API 1 // 2021 API: forward_comm_fix / reverse_comm_fix
#define fibre_forward_comm(comm, fix, n) (comm)->forward_comm_fix((fix), (n))
#define fibre_reverse_comm(comm, fix, n) (comm)->reverse_comm_fix_variable((fix))
#define FIBRE_PACK_FORWARD pack_forward_comm
#define FIBRE_UNPACK_FORWARD unpack_forward_comm
#endif
