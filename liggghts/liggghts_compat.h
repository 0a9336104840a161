// Compatibility layer for LIGGGHTS 3.8 (Debian's libliggghts-dev), force-included before any
// LIGGGHTS header when the shared front-end sources in fix/ are compiled for liggghts_fibre.
// What differs from LAMMPS 29 Sep 2021 is listed in fix/host.h; here are the names the fix
// declares: LIGGGHTS's forward communication callbacks are pack_comm/unpack_comm, and
// comm->forward_comm_fix(fix) takes its size from the fix's comm_forward.
#pragma once

#define FIBRE_HOST_LIGGGHTS 1

#ifdef __cplusplus
#define fibre_forward_comm(comm, fix, n) (comm)->forward_comm_fix((fix))
#define fibre_reverse_comm(comm, fix, n) (comm)->reverse_comm_fix((fix))
#define FIBRE_PACK_FORWARD pack_comm
#define FIBRE_UNPACK_FORWARD unpack_comm
#endif
