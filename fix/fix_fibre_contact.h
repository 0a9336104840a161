/* -*- c++ -*- ----------------------------------------------------------
   fix fibre_contact: nonsmooth, regularized (SPOOK) contact dynamics for granular spheres,
   solved with preconditioned Krylov methods (fibre preconditioner) or MUMPS.
   Documentation: doc/fix_fibre_contact.md
------------------------------------------------------------------------- */

#ifndef LMP_FIX_FIBRE_CONTACT_H
#define LMP_FIX_FIBRE_CONTACT_H

#include <memory>
#include <string>
#include <vector>

#include "fibre/step_solver.hpp"
#include "fix.h"

namespace fibre_lmp {
class LammpsExchange;
}

namespace LAMMPS_NS {

class FixFibreContact : public Fix {
 public:
  FixFibreContact(class LAMMPS *, int, char **);
  ~FixFibreContact() override;
  int setmask() override;
  void init() override;
  void setup(int) override;
  void initial_integrate(int) override;
  void final_integrate() override;
  void reset_dt() override;

  double compute_vector(int) override;

  void write_restart(FILE *) override;
  void restart(char *) override;

  void grow_arrays(int) override;
  void copy_arrays(int, int, int) override;
  void set_arrays(int) override;
  int pack_exchange(int, double *) override;
  int unpack_exchange(int, double *) override;
  int pack_restart(int, double *) override;
  void unpack_restart(int, int) override;
  int size_restart(int) override;
  int maxsize_restart() override;

  int pack_forward_comm(int, int *, double *, int, int *) override;
  void unpack_forward_comm(int, int, double *) override;
  int pack_reverse_comm(int, int, double *) override;
  void unpack_reverse_comm(int, int *, double *) override;

  double memory_usage() override;

  // Warm-start storage: per atom up to kMaxSlots contacts, each kSlotSize doubles:
  // partner key (tag of the other atom, or -(wall key)), then force and torque (world frame,
  // impulse / dt) acting on the contact's first body.
  static constexpr int kMaxSlots = 16;
  static constexpr int kSlotSize = 7;

  enum WallKind { XPLANE = 0, YPLANE = 1, ZPLANE = 2, REGION = 3 };
  struct Wall {
    WallKind kind = ZPLANE;
    bool has_lo = false, has_hi = false;
    double lo = 0.0, hi = 0.0;
    std::string region_id;
    int iregion = -1;  // looked up in init()
  };

  // One detected contact before the system is built.
  struct Found {
    fibre::Contact contact;
    tagint tag_a = 0;
    double partner = 0;  // tag of body b / obstacle atom (> 0), or -(wall key) (< 0)
    int wall = -1;       // index into walls_ for wall contacts, else -1
    int store_atom = -1; // local atom that keeps this contact's warm start
  };

 protected:
  void parse_args(int narg, char **arg);
  [[noreturn]] void illegal(const std::string &expected, const char *got = nullptr);
  double parse_number(int narg, char **arg, int iarg, const std::string &expected);
  double parse_positive(int narg, char **arg, int iarg, const std::string &expected);
  long parse_integer(int narg, char **arg, int iarg, const std::string &expected, long lo,
                     long hi);
  void check_pair_style(bool at_init);

  void build_bodies(std::vector<fibre::Body> &bodies);
  void detect_pair_contacts(const std::vector<fibre::Body> &bodies, std::vector<Found> &found);
  void detect_wall_contacts(const std::vector<fibre::Body> &bodies, std::vector<Found> &found);
  void add_wall_contact(const std::vector<fibre::Body> &bodies, int body, const double *normal,
                        double distance, int wall, int sub, std::vector<Found> &found);
  bool approaching(const fibre::Body &a, const fibre::Body *b, const fibre::Vec3 &n,
                   double gap) const;
  void set_compliance(std::vector<Found> &found, const std::vector<fibre::Body> &bodies);
  void warm_start(const std::vector<Found> &found, int rows, fibre::Vector &warm) const;
  void store_impulses(const std::vector<Found> &found, const fibre::ContactSystem &sys,
                      const fibre::Vector &lambda);
  void update_velocities(const fibre::Vector *dv);
  void check_finite(const char *what, double **array, int nvalues) const;
  void fill_local_output(const std::vector<Found> &found, const fibre::Vector *lambda);
  void export_system(const fibre::ContactSystem &sys, const std::vector<Found> &found,
                     const fibre::Vector *lambda);
  void report_solve(const fibre::StepResult &res);

  // settings
  fibre::StepOptions opt_;
  bool compliance_auto_ = true;
  double compliance_n_ = 0.0, compliance_t_ = 0.0;
  double compliance_factor_ = 1e-2;  // auto: eps = factor * dt^2 / m_min
  double damping_ = 2.0;
  int rows_ = 6;
  std::vector<Wall> walls_;
  int export_every_ = 0;
  std::string export_prefix_;

  // state
  double dtv_ = 0.0;
  class Pair *pair_ = nullptr;  // pair style whose force computation this fix switched off
  std::unique_ptr<fibre_lmp::LammpsExchange> exchange_;
  std::vector<int> atom_body_;  // local atom -> body index, -1 if not a body
  int nslot_max_ = 0;           // allocated rows of the per-atom arrays
  int *nslot_ = nullptr;        // per atom: number of stored contacts
  double **slots_ = nullptr;    // per atom: kMaxSlots * kSlotSize values
  bigint overflow_count_ = 0;
  bool overflow_warned_ = false;

  // statistics (global vector)
  enum {
    V_ITER = 0, V_RESID, V_CONTACTS, V_FIBRES, V_FIBRE_FRACTION, V_PASSES, V_OVERLAP,
    V_SETUP, V_SOLVE, V_CONVERGED, V_WALL_CONTACTS, V_NONCONVERGED, V_COMPLEMENTARITY, V_SWEEPS,
    V_SWEEP_TIME, V_SIZE
  };
  double stats_[V_SIZE] = {};
  bigint nonconverged_total_ = 0;
  bigint nonconverged_since_warning_ = 0;
  bigint last_warning_step_ = -1;
  double last_m_min_ = 0.0;

  // local output: one row per contact owned by this process
  int maxlocal_ = 0;
  double **local_array_ = nullptr;
};

}  // namespace LAMMPS_NS

#endif
