/* -*- c++ -*- ----------------------------------------------------------
   fix fibre_contact: nonsmooth, regularized (SPOOK) contact dynamics for granular spheres,
   solved by the fibre solver library. Documentation: doc/fix_fibre_contact.md
------------------------------------------------------------------------- */

#ifndef LMP_FIX_FIBRE_CONTACT_H
#define LMP_FIX_FIBRE_CONTACT_H

#include <array>
#include <memory>
#include <vector>

#include "fibre/frontend/settings.hpp"
#include "fibre/model/contact_history.hpp"
#include "fibre/step/substeps.hpp"
#include "fix.h"

namespace fibre_lmp {
class LammpsExchange;
class LammpsDetection;
class FibreOutput;
class LammpsClumps;
} // namespace fibre_lmp

namespace LAMMPS_NS {

class FixFibreContact : public Fix {
 public:
  FixFibreContact(class LAMMPS *, int, char **);
  ~FixFibreContact() override;
  int setmask() override;
  void init() override;
  void setup(int) override;
  void initial_integrate(int) override;
  void post_force(int) override;
  void final_integrate() override;
  void post_run() override;
  void reset_dt() override;

  double compute_vector(int) override;
  double compute_array(int, int) override;

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

  // pack_forward_comm/unpack_forward_comm (LAMMPS), pack_comm/unpack_comm (LIGGGHTS)
  int FIBRE_PACK_FORWARD(int, int *, double *, int, int *) override;
  void FIBRE_UNPACK_FORWARD(int, int, double *) override;
  int pack_reverse_comm(int, int, double *) override;
  void unpack_reverse_comm(int, int *, double *) override;
#ifndef FIBRE_HOST_LIGGGHTS
  int pack_reverse_comm_size(int, int) override;
#endif

  double memory_usage() override;

 protected:
  void start_virial(int vflag);
  void check_pair_style(bool at_init);
  void warn_double_integration();
  void warn_pair_computes();
  void warn_short_damping();
  void check_neighbor_updates();
  void read_coefficients();
  void check_finite(const char *what, double **array, int nvalues) const;
  void smallest_body(const std::vector<fibre::Body> &bodies);
  double bounce_speed(const std::vector<fibre::Body> &bodies, double h) const;
  double impact_speed(const std::vector<fibre::Body> &bodies, double h) const;
  bool step_moves(const std::vector<fibre::Body> &bodies,
                  const std::vector<fibre::Contact> &contacts, double hs) const;
  void follow_substeps(const fibre::Vector &path, int n, double hs);
  bool recover_penetrations(fibre::Substeps &steps);
  int step_substeps();
  bool note_moving_walls(const std::vector<fibre::Contact> &contacts);
  std::string step_advice(double t_c) const;
  double simulated_time() const;
  void tally_wall_loads(const fibre::ContactSystem &sys, const std::vector<fibre::ContactTag> &tags,
                        const fibre::Vector &lambda);
  void tally_virial(const fibre::ContactSystem &sys, const fibre::Vector &lambda);
  void warn_skin();
  void warn_deep_overlaps(const std::vector<fibre::Body> &bodies,
                          const std::vector<fibre::Contact> &contacts, double max_recovery);
  fibre::StepResult solve(fibre::ContactSystem &sys, const fibre::Vector &warm,
                          const fibre::StepOptions &opt, fibre::SweepCache *cache);
  void check_step(const fibre::Substeps &steps, int substeps, const fibre::SpookParams &params,
                  std::vector<fibre::Body> bodies, std::vector<fibre::Contact> contacts,
                  fibre::Vector warm);
  void update_velocities(const fibre::Vector *dv);
  int solve_interval() const;
  void follow_solve_step(int every);
  void hold_step();
  fibre::SpookParams step_params(const std::vector<fibre::Body> &bodies, double h) const;
  fibre::Substeps solve_contacts(std::vector<fibre::Body> bodies, fibre::FoundContacts &found,
                                 int &substeps, double &hs);
  void report_step(const fibre::Substeps &steps, const std::vector<fibre::ContactTag> &tags,
                   bool any, bool solved);

  fibre::Settings settings_;
  double dtv_ = 0.0;
  // contact_every: the contact solve's step h_ (dtv_ times the steps to the next solve) and the
  // step of the next solve; between solves the velocities take the external forces only, and
  // the outputs and the global virial are the last solve's
  double h_ = 0.0;
  bigint next_solve_ = 0;
  double held_virial_[6] = {0, 0, 0, 0, 0, 0};
  double time_origin_ = 0.0; // simulated time when the fix was defined (moving planes)
  static constexpr double kDeepOverlap = 0.05; // of the smaller diameter: warned at a run's start
  double m_min_ = 0.0, r_min_ = 0.0;
  double fastest_ = 0.0;     // the step's largest free speed of a sphere (smallest_body)
  bool skin_warned_ = false; // warn_skin, once a run
  bool first_step_ = true;
  bool recovering_ = false;          // the last step opened rigid rows' penetrations (recovery.hpp)
  double step_logged_ = 0.0;         // the step whose ratio to the collision time the log states
  int substeps_logged_ = 0;          // and its substeps
  class Pair *pair_ = nullptr;       // pair style whose force computation this fix switched off
  class Pair *pair_owner_ = nullptr; // the deck's pair style then (pair_ or its hybrid)
  std::unique_ptr<fibre_lmp::LammpsExchange> exchange_;
  std::unique_ptr<fibre_lmp::LammpsDetection> detection_;
  std::unique_ptr<fibre_lmp::FibreOutput> output_;
  std::unique_ptr<fibre_lmp::LammpsClumps> clumps_; // clumps molecule, else null
  bool forward_clumps_ = false;                     // the forward comm is the clumps' state
  fibre::ContactHistory history_;
  // Per atom: the substeps' displacement beyond dt v (follow_substeps), added at the next
  // step's start, so that between steps the positions are the step's own.
  std::vector<std::array<double, 3>> pending_;
  static constexpr int kPendingValues = 3;
  long overflow_count_ = 0;
  bool overflow_warned_ = false;
  bool jammed_warned_ = false;             // penetrations without room to open, warned once
  static constexpr int kRecoveryWait = 32; // the longest wait for room (recover_penetrations)
  int recovery_backoff_ = 0;               // the last wait for room, steps
  int recovery_wait_ = 0;                  // steps left before the next recovery solve
  bool moving_walls_met_ = false;          // a solve over several steps met a moving wall
};

} // namespace LAMMPS_NS

#endif
