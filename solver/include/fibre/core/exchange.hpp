// The communicator interface of the solver library (doc/design.md section 6).
//
// The library never calls MPI itself for halo data: the front end (the LAMMPS fix) implements
// forward/reverse exchange of per-body vectors, and global sums. Serial runs and unit tests
// use SerialExchange.
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "fibre/core/system.hpp"

namespace fibre {

// The body that holds a local body's velocity under Exchange::local_owners: itself, or a
// periodic image's body; -1 (a wall) stays.
inline int owner_of(const std::vector<int> &owners, int body)
{
  return owners.empty() || body < 0 ? body : owners[body];
}

class Exchange {
 public:
  virtual ~Exchange() = default;
  // Per-body vector (6 per body, owned then ghosts): copy every owner's value to its ghosts.
  virtual void forward(Vector &body_vec) const = 0;
  // Add every ghost's value into its owner, then zero the ghosts.
  virtual void reverse_sum(Vector &body_vec) const = 0;
  // False when forward and reverse_sum do nothing (one process and no ghost bodies), so that
  // callers may skip the copies around them.
  virtual bool has_halo() const { return true; }
  // Global sum over all processes, in place.
  virtual void sum(double *values, int n) const = 0;
  // Global maximum over all processes, in place.
  virtual void max(double *values, int n) const = 0;

  // Exclusive prefix sum over processes in rank order (0 on the first).
  virtual long exclusive_prefix_sum(long local) const = 0;
  // For every local body, the body of this process that holds its velocity: itself, or for a
  // ghost that is a periodic image of a body owned here, that body. Gauss-Seidel sweeps update
  // it in place (the images of one body must not relax apart within a sweep). Empty: itself.
  virtual const std::vector<int> &local_owners() const
  {
    static const std::vector<int> none;
    return none;
  }

  // The copies of the bodies that contacts move, for solvers that exchange per-body changes
  // many times over one fixed set of contacts (the sweeps: once per sweep).
  class Halo {
   public:
    virtual ~Halo() = default;
    // Every copy of a body that some process touches gets the sum of all its copies' values:
    // reverse_sum, then forward, on those bodies only. Copies that no process touches, and
    // ghosts that this process does not touch, keep their values.
    virtual void sum_copies(Vector &body_vec) const = 0;
    // The local bodies whose entries sum_copies reads or writes, ascending; null: every body.
    // The sweeps then carry only these bodies' changes around the exchange.
    virtual const std::vector<int> *bodies() const { return nullptr; }
    // Two colours for the processes, so that as few processes as may be that touch a common
    // body share a colour (alike on every process): the sweeps visit the contacts on shared
    // bodies one colour at a time, as one process would, and split the masses of the bodies
    // that processes of one colour share (pgs.hpp). One colour: none (every shared body split).
    virtual int colours() const { return 1; }
    virtual int colour() const { return 0; }
  };
  // touched: one flag per local body (owned, then ghosts), set where this process's contacts
  // move it. colour: whether the caller sweeps by Halo::colours (else one colour, and the
  // colouring's collective is spared). A collective. The default sums every body's copies.
  virtual std::unique_ptr<Halo> halo(const std::vector<char> &touched, bool colour) const;

  double sum(double x) const
  {
    sum(&x, 1);
    return x;
  }
  double max(double x) const
  {
    max(&x, 1);
    return x;
  }
};

// One process, no ghosts.
class SerialExchange final : public Exchange {
 public:
  void forward(Vector &) const override {}
  void reverse_sum(Vector &) const override {}
  bool has_halo() const override { return false; }
  void sum(double *, int) const override {}
  void max(double *, int) const override {}
  long exclusive_prefix_sum(long) const override { return 0; }
};

// One process whose ghosts are periodic images of its own bodies: a serial periodic step
// replayed from an export (its PREFIX.images). An image holds its body's velocity, and what
// its contacts do to it is done to the body.
class ImageExchange final : public Exchange {
 public:
  // owners: for every local body, itself or, for an image, its body (an owned one)
  explicit ImageExchange(std::vector<int> owners) : owners_(std::move(owners)) {}
  void forward(Vector &body_vec) const override;
  void reverse_sum(Vector &body_vec) const override;
  void sum(double *, int) const override {}
  void max(double *, int) const override {}
  long exclusive_prefix_sum(long) const override { return 0; }
  const std::vector<int> &local_owners() const override { return owners_; }

 private:
  std::vector<int> owners_;
};

// Index of every local body (owned, then ghosts) in one global numbering of all owned bodies
// of all processes; `total` receives their count. Uses exclusive_prefix_sum and forward.
std::vector<long> global_body_index(const Exchange &ex, int num_owned, int num_bodies, long &total);

const Exchange &serial_exchange();

} // namespace fibre
