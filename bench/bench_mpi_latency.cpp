// Latency of the MPI operations a Krylov iteration makes under `mpirun -np P`: MPI_Allreduce
// of one double (every inner product) and a neighbour exchange of a small buffer (the halo
// forward/reverse of the body vectors, 48 bytes per ghost body). A parallel solve pays about
// 3 allreduces and 2 halo exchanges per iteration, so these numbers bound its strong scaling:
// an iteration cannot take less than 3 t_allreduce + 2 t_exchange.
//   mpirun -np 2 build-perf/bench/bench_mpi_latency [ghost_bodies]
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

int main(int argc, char **argv)
{
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int ghosts = argc > 1 ? std::atoi(argv[1]) : 150;
  const int reps = 2000;
  std::vector<double> t_all, t_x;
  std::vector<double> send(6 * std::size_t(ghosts), 1.0), recv(send.size());
  const int right = (rank + 1) % size, left = (rank + size - 1) % size;
  for (int round = 0; round < 5; ++round) {
    MPI_Barrier(MPI_COMM_WORLD);
    double x = 1.0, t0 = MPI_Wtime();
    for (int i = 0; i < reps; ++i)
      MPI_Allreduce(MPI_IN_PLACE, &x, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    t_all.push_back((MPI_Wtime() - t0) / reps);
    MPI_Barrier(MPI_COMM_WORLD);
    t0 = MPI_Wtime();
    for (int i = 0; i < reps; ++i)
      MPI_Sendrecv(send.data(), int(send.size()), MPI_DOUBLE, right, 0, recv.data(),
                   int(recv.size()), MPI_DOUBLE, left, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    t_x.push_back((MPI_Wtime() - t0) / reps);
  }
  std::sort(t_all.begin(), t_all.end());
  std::sort(t_x.begin(), t_x.end());
  if (rank == 0)
    std::printf("bench_mpi_latency: %d ranks; MPI_Allreduce(1 double) %.2f us, halo exchange "
                "(%d ghost bodies, %zu B) %.2f us (median of 5 x %d); one Krylov iteration "
                ">= %.1f us of communication\n",
                size, 1e6 * t_all[2], ghosts, 8 * send.size(), 1e6 * t_x[2], reps,
                1e6 * (3 * t_all[2] + 2 * t_x[2]));
  MPI_Finalize();
  return 0;
}
