// The solver library's communicator interface (fibre::Exchange) implemented with LAMMPS's
// halo communication, for fix fibre_contact.
//
// Bodies are atoms: body k of the contact system is local atom body_atom[k], owned bodies
// first, then ghosts. forward() and reverse_sum() move 6 doubles per atom through the fix's
// pack/unpack_forward_comm and pack/unpack_reverse_comm (comm_forward = comm_reverse = 6);
// under comm_style tiled reverse_sum() goes point to point to the ghosts' owners instead. The
// global reductions use MPI on the fix's world communicator.
#pragma once

#include <mpi.h>

#include <memory>
#include <unordered_map>
#include <vector>

#include "fibre/core/exchange.hpp"
#include "lmptype.h"

namespace LAMMPS_NS {
class LAMMPS;
class Fix;
} // namespace LAMMPS_NS

namespace fibre_lmp {

class PointHalo;

class LammpsExchange final : public fibre::Exchange {
 public:
  static constexpr int kValuesPerAtom = 6;

  LammpsExchange(LAMMPS_NS::LAMMPS *lmp, LAMMPS_NS::Fix *fix, MPI_Comm world);
  ~LammpsExchange() override;
  LammpsExchange(const LammpsExchange &) = delete;
  LammpsExchange &operator=(const LammpsExchange &) = delete;

  // Body k <-> local atom body_atom[k]; bodies [0, num_owned) are owned atoms (< nlocal).
  void set_bodies(const std::vector<int> &body_atom, int num_owned);
  int num_owned() const { return num_owned_; }
  const std::vector<int> &body_atom() const { return body_atom_; }

  void forward(fibre::Vector &body_vec) const override;
  void reverse_sum(fibre::Vector &body_vec) const override;
  bool has_halo() const override { return has_halo_; }
  void sum(double *values, int n) const override;
  void max(double *values, int n) const override;
  long exclusive_prefix_sum(long local) const override;
  // Point to point between the processes that share the touched bodies (lammps_exchange.cpp).
  std::unique_ptr<Halo> halo(const std::vector<char> &touched, bool colour) const override;
  const std::vector<int> &local_owners() const override { return local_owners_; }
  using fibre::Exchange::max;
  using fibre::Exchange::sum;

  // Called from the fix's pack/unpack methods: 6 values per atom from/to the halo buffer.
  int pack_forward(int n, const int *list, double *buf) const;
  void unpack_forward(int first, int n, const double *buf) const;
  int pack_reverse(int first, int n, double *buf) const;
  void unpack_reverse(int n, const int *list, const double *buf) const;

 private:
  void resize_halo() const;
  std::unique_ptr<PointHalo> point_halo(const std::vector<char> &touched, bool colour) const;
  bool comm_tiled() const;
  // The owner process of every ghost body (-1 for owned ones), by a forward comm once per set
  // of bodies.
  const std::vector<int> &ghost_owners() const;

  LAMMPS_NS::LAMMPS *lmp_;
  LAMMPS_NS::Fix *fix_;
  MPI_Comm world_;
  std::vector<int> body_atom_;
  int num_owned_ = 0;
  std::vector<int> local_owners_; // periodic images of owned bodies -> those bodies
  std::unordered_map<LAMMPS_NS::tagint, int> owned_body_; // an owned body's tag -> its index
  mutable std::vector<int> ghost_owners_;
  mutable bool ghost_owners_known_ = false;
  MPI_Comm halo_comm_ = MPI_COMM_NULL; // the sweeps' messages, apart from LAMMPS's
  bool has_halo_ = true;               // other processes, or ghost bodies here
  mutable std::vector<double> halo_;   // 6 per local atom (owned + ghost)
  // comm_style tiled's reverse sum: every ghost body's link to its owner, once per set of bodies
  mutable std::unique_ptr<PointHalo> every_ghost_;
};

} // namespace fibre_lmp
