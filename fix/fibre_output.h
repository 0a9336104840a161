// What fix fibre_contact reports: the global vector f_ID[1..18], the wall loads f_ID[w][1..6],
// the local array (one row per contact kept by this process), the non-convergence warnings and
// the system exports.
#pragma once

#include <string>
#include <vector>

#include "fibre/algebra/spook.hpp"
#include "fibre/geometry/detection.hpp"
#include "fibre/model/stress.hpp"
#include "fibre/step/step_solver.hpp"
#include "fibre/study/nonsmooth_reference.hpp"
#include "pointers.h"

namespace fibre_lmp {

// Entries of the global vector (f_ID[k + 1]); the doc page's "Restart, fix_modify, output"
// lists them.
enum Stat {
  V_ITER = 0,
  V_RESID,
  V_CONTACTS,
  V_FIBRES,
  V_FIBRE_FRACTION,
  V_PASSES,
  V_OVERLAP,
  V_SETUP,
  V_SOLVE,
  V_CONVERGED,
  V_WALL_CONTACTS,
  V_NONCONVERGED,
  V_COMPLEMENTARITY,
  V_SWEEPS,
  V_SWEEP_TIME,
  V_ERROR_ESTIMATE,
  V_WALL_WORK,      // cumulative, since the fix was defined (kept across restarts)
  V_DISSIPATION,    // cumulative, likewise
  V_CHECK_VELOCITY, // the last check's errors against the converged step (keyword check)
  V_CHECK_IMPULSE,
  V_SUBSTEPS, // the last step's contact solves (its substeps; 1 where nothing moved)
  V_SPLIT,    // the last step's penetrations opened by the split recovery
  V_RESTARTS, // solves whose slow sweeps started again (restart_sweeps), cumulative
  V_SIZE
};

class FibreOutput : protected LAMMPS_NS::Pointers {
 public:
  static constexpr int kLocalColumns = 8;
  static constexpr double kRestartFormat = 8.0; // 8: 23 global values (7: 22, 6: 21, 5: 20, ...)

  explicit FibreOutput(LAMMPS_NS::LAMMPS *lmp) : Pointers(lmp)
  {
    stats_[V_CHECK_VELOCITY] = stats_[V_CHECK_IMPULSE] = -1.0; // no check yet
  }
  ~FibreOutput() override;

  double stat(int n) const { return n >= 0 && n < V_SIZE ? stats_[n] : 0.0; }
  // The last step's load on wall w: force x, y, z and torque about the origin x, y, z.
  void set_wall_loads(const std::vector<fibre::WallLoad> &loads) { wall_loads_ = loads; }
  double wall_load(int w, int column) const
  {
    return w >= 0 && w < static_cast<int>(wall_loads_.size()) && column >= 0 && column < 6
               ? wall_loads_[w][column]
               : 0.0;
  }

  // Contacts, wall contacts and the deepest overlap over all processes, a clump's joints not
  // counted; returns the number of contacts and joints (zero: free flight).
  double count_contacts(const std::vector<fibre::Contact> &contacts);
  // The solve's figures (summed or maximised over processes), with a warning at most every
  // 100 steps while solves fail. A step without contacts reports an empty, converged result.
  void report_solve(const fibre::StepResult &res);
  void report_substeps(int done) { stats_[V_SUBSTEPS] = done; }
  void report_split(long penetrations) { stats_[V_SPLIT] = static_cast<double>(penetrations); }
  // Adds one step's work of the contacts (this process's contacts; summed here).
  void add_work(const fibre::ContactWork &work);
  // A check's errors (keyword check), with a warning where its reference did not converge.
  void report_check(const fibre::StepAccuracy &errors, bool reference_converged, int sweeps);
  // One row per contact: tags, wall, gap, |normal|, |friction|, |rolling|, |twisting| impulse.
  void fill_local(const std::vector<fibre::ContactTag> &tags, const fibre::Vector *lambda, int rows,
                  double **&array_local, int &size_local_rows);
  // Frees the rows before a solve, which has no use for them (fill_local makes them again,
  // as many as the contacts): the solve's peak memory holds no copy of the last step's.
  void release_local(double **&array_local, int &size_local_rows);
  // prefix.STEP.RANK.sys (the system) and .lambda (the atoms of every contact, its impulses and
  // the warm start the solve began from): together the whole step, to replay it; and .images
  // (image body, per line) where ghosts are periodic images of this process's bodies (owners:
  // Exchange::local_owners).
  void export_step(const std::string &prefix, const fibre::ContactSystem &sys,
                   const std::vector<fibre::ContactTag> &tags, const fibre::Vector *lambda,
                   const fibre::Vector &warm, const std::vector<int> &owners);

  void write_restart(FILE *fp) const;
  void read_restart(const char *buf);
  double memory_bytes() const;

 private:
  double stats_[V_SIZE] = {};
  std::vector<fibre::WallLoad> wall_loads_;
  LAMMPS_NS::bigint nonconverged_total_ = 0;
  LAMMPS_NS::bigint nonconverged_since_warning_ = 0;
  LAMMPS_NS::bigint last_warning_step_ = -1;
  LAMMPS_NS::bigint last_restart_warning_ = -1;
  int maxlocal_ = 0;
  double **local_array_ = nullptr;
};

} // namespace fibre_lmp
