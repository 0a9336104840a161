#include "fibre_output.h"

#include <cmath>
#include <cstdio>
#include <exception>

#include "comm.h"
#include "error.h"
#include "host.h"
#include "fibre/core/text.hpp"
#include "fibre/io/system_io.hpp"
#include "fibre/step/substeps.hpp"
#include "memory.h"
#include "update.h"

using namespace LAMMPS_NS;

namespace fibre_lmp {

FibreOutput::~FibreOutput()
{
  memory->destroy(local_array_);
}

double FibreOutput::count_contacts(const std::vector<fibre::Contact> &contacts)
{
  // contacts, wall contacts, and every row block of the system (a clump's joints too)
  double sums[3] = {0.0, 0.0, double(contacts.size())};
  double deepest = 0.0;
  for (const fibre::Contact &c : contacts) {
    if (c.is_joint()) continue;
    sums[0] += 1.0;
    if (c.is_wall()) sums[1] += 1.0;
    deepest = std::max(deepest, -c.gap);
  }
  MPI_Allreduce(MPI_IN_PLACE, sums, 3, MPI_DOUBLE, MPI_SUM, world);
  MPI_Allreduce(MPI_IN_PLACE, &deepest, 1, MPI_DOUBLE, MPI_MAX, world);
  stats_[V_CONTACTS] = sums[0];
  stats_[V_WALL_CONTACTS] = sums[1];
  stats_[V_OVERLAP] = deepest;
  return sums[2];
}

void FibreOutput::report_solve(const fibre::StepResult &res)
{
  stats_[V_ITER] = res.total_iterations;
  stats_[V_RESID] = res.rel_residual;
  stats_[V_PASSES] = res.active_set_passes;
  stats_[V_CONVERGED] = res.converged ? 1.0 : 0.0;
  stats_[V_COMPLEMENTARITY] = res.complementarity;
  stats_[V_SWEEPS] = res.sweeps;
  stats_[V_ERROR_ESTIMATE] = res.error_estimate;
  stats_[V_RESTARTS] += res.slow_restarts; // alike on every process

  double sums[3] = {double(res.fibres.num_fibres), double(res.fibres.contacts_in_fibres),
                    double(res.fibres.num_contacts)};
  MPI_Allreduce(MPI_IN_PLACE, sums, 3, MPI_DOUBLE, MPI_SUM, world);
  stats_[V_FIBRES] = sums[0];
  stats_[V_FIBRE_FRACTION] = sums[2] > 0 ? sums[1] / sums[2] : 0.0;
  double times[3] = {res.setup_seconds, res.solve_seconds, res.sweep_seconds};
  MPI_Allreduce(MPI_IN_PLACE, times, 3, MPI_DOUBLE, MPI_MAX, world);
  stats_[V_SETUP] = times[0];
  stats_[V_SOLVE] = times[1];
  stats_[V_SWEEP_TIME] = times[2];

  if (res.restarted && comm->me == 0 &&
      (last_restart_warning_ < 0 || update->ntimestep - last_restart_warning_ >= 100)) {
    warn(error, FLERR,
         "Fix fibre_contact: at step " + std::to_string(static_cast<long long>(update->ntimestep)) +
             " the linear pass left the impulses worse than the warm start; "
             "the sweeps restarted from the warm start (complementarity " +
             fibre::format_g(res.complementarity) + ")");
    last_restart_warning_ = update->ntimestep;
  }
  if (!res.converged) {
    ++nonconverged_total_;
    ++nonconverged_since_warning_;
    const bigint step = update->ntimestep;
    if (last_warning_step_ < 0 || step - last_warning_step_ >= 100) {
      if (comm->me == 0) {
        std::string why = std::string(fibre::to_string(res.reason)) + ", ";
        if (res.total_iterations > 0) // a linear pass ran (a sweeps-only solve has none)
          why += std::to_string(res.iterations) + " iterations, relative residual " +
                 fibre::format_g(res.rel_residual) + ", ";
        why += std::to_string(res.sweeps) + " sweeps, error estimate " +
               fibre::format_g(res.error_estimate) + ", complementarity " +
               fibre::format_g(res.complementarity);
        warn(error, FLERR,
             "Fix fibre_contact: contact solve did not converge at step " +
                 std::to_string(static_cast<long long>(step)) + " (" + why +
                 "); the step keeps these impulses; " +
                 std::to_string(static_cast<long long>(nonconverged_since_warning_)) +
                 " non-converged steps since the last warning, " +
                 std::to_string(static_cast<long long>(nonconverged_total_)) +
                 " in all (f_ID[12])");
      }
      last_warning_step_ = step;
      nonconverged_since_warning_ = 0;
    }
  }
  stats_[V_NONCONVERGED] = static_cast<double>(nonconverged_total_);
}

void FibreOutput::fill_local(const std::vector<fibre::ContactTag> &tags,
                             const fibre::Vector *lambda, int rows, double **&array_local,
                             int &size_local_rows)
{
  const int nc = static_cast<int>(tags.size());
  if (nc > maxlocal_) {
    maxlocal_ = nc;
    memory->destroy(local_array_);
    memory->create(local_array_, maxlocal_, kLocalColumns, "fibre_contact:local");
  }
  array_local = local_array_;
  size_local_rows = nc;
  for (int c = 0; c < nc; ++c) {
    const fibre::ContactTag &fc = tags[c];
    double *row = local_array_[c];
    row[0] = static_cast<double>(fc.tag_a);
    row[1] = fc.partner > 0 ? fc.partner : 0.0;
    row[2] = fc.wall + 1;
    row[3] = fc.gap;
    for (int d = 4; d < kLocalColumns; ++d) row[d] = 0.0;
    if (!lambda) continue;
    const double *l = lambda->data() + Eigen::Index(rows) * c;
    row[4] = l[0];
    // sqrt, not std::hypot: impulses do not overflow, and hypot's care was 2% of a step
    row[5] = std::sqrt(l[1] * l[1] + l[2] * l[2]);
    if (rows == 6) {
      row[6] = std::sqrt(l[4] * l[4] + l[5] * l[5]);
      row[7] = std::fabs(l[3]);
    }
  }
}

void FibreOutput::release_local(double **&array_local, int &size_local_rows)
{
  memory->destroy(local_array_);
  local_array_ = nullptr;
  maxlocal_ = 0;
  array_local = nullptr;
  size_local_rows = 0;
}

void FibreOutput::export_step(const std::string &prefix, const fibre::ContactSystem &sys,
                              const std::vector<fibre::ContactTag> &tags,
                              const fibre::Vector *lambda, const fibre::Vector &warm,
                              const std::vector<int> &owners)
{
  const std::string base = prefix + "." +
                           std::to_string(static_cast<long long>(update->ntimestep)) + "." +
                           std::to_string(comm->me);
  try {
    fibre::write_system_file(base + ".sys", sys);
  } catch (std::exception &e) {
    fail_one(error, FLERR,
             "Fix fibre_contact could not write export file " + base + ".sys: " + e.what());
  }
  FILE *fp = std::fopen((base + ".lambda").c_str(), "w");
  if (!fp)
    fail_one(error, FLERR, "Fix fibre_contact could not write export file " + base + ".lambda");
  const int rows = sys.rows();
  std::fprintf(fp, "# fibre_contact impulses, step %lld, process %d: %d contacts, %d rows each\n",
               static_cast<long long>(update->ntimestep), comm->me, sys.num_contacts(), rows);
  std::fprintf(fp,
               "# contact tag_a tag_b(0 = wall) wall(0 = none) lambda_0 .. lambda_%d warm_0 .. "
               "warm_%d\n",
               rows - 1, rows - 1);
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const fibre::ContactTag &fc = tags[c];
    std::fprintf(fp, "%d %lld %lld %d", c, static_cast<long long>(fc.tag_a),
                 static_cast<long long>(fc.partner > 0 ? fc.partner : 0.0), fc.wall + 1);
    const Eigen::Index at = Eigen::Index(rows) * c;
    for (int r = 0; r < rows; ++r) std::fprintf(fp, " %.17g", lambda ? (*lambda)[at + r] : 0.0);
    for (int r = 0; r < rows; ++r)
      std::fprintf(fp, " %.17g", warm.size() > at + r ? warm[at + r] : 0.0);
    std::fprintf(fp, "\n");
  }
  std::fclose(fp);
  // the ghosts that are periodic images of this process's own bodies, for an exact replay
  std::vector<int> images;
  for (int i = 0; i < static_cast<int>(owners.size()); ++i)
    if (owners[i] != i) images.push_back(i);
  if (images.empty()) return;
  fp = std::fopen((base + ".images").c_str(), "w");
  if (!fp)
    fail_one(error, FLERR, "Fix fibre_contact could not write export file " + base + ".images");
  std::fprintf(fp, "# fibre_contact periodic images, step %lld, process %d: image body\n",
               static_cast<long long>(update->ntimestep), comm->me);
  for (int i : images) std::fprintf(fp, "%d %d\n", i, owners[i]);
  std::fclose(fp);
}

void FibreOutput::add_work(const fibre::ContactWork &work)
{
  double sums[2] = {work.wall_work, work.dissipation};
  MPI_Allreduce(MPI_IN_PLACE, sums, 2, MPI_DOUBLE, MPI_SUM, world);
  stats_[V_WALL_WORK] += sums[0];
  stats_[V_DISSIPATION] += sums[1];
}

void FibreOutput::report_check(const fibre::StepAccuracy &errors, bool reference_converged,
                               int sweeps)
{
  stats_[V_CHECK_VELOCITY] = errors.velocity();
  stats_[V_CHECK_IMPULSE] = errors.impulse();
  if (reference_converged || comm->me != 0) return;
  warn(error, FLERR,
       "Fix fibre_contact: the check's converged step at step " +
           std::to_string(static_cast<long long>(update->ntimestep)) + " did not reach " +
           fibre::format_g(fibre::kCheckAccuracy) + " in " + std::to_string(sweeps) +
           " sweeps; its errors (f_ID[19], f_ID[20]) are against that");
}

// Counters and the last step's figures.
void FibreOutput::write_restart(FILE *fp) const
{
  double list[2 + V_SIZE];
  list[0] = kRestartFormat;
  list[1] = static_cast<double>(nonconverged_total_);
  for (int k = 0; k < V_SIZE; ++k) list[2 + k] = stats_[k];
  if (comm->me == 0) {
    const int size = static_cast<int>(sizeof(list));
    std::fwrite(&size, sizeof(int), 1, fp);
    std::fwrite(list, sizeof(double), 2 + V_SIZE, fp);
  }
}

void FibreOutput::read_restart(const char *buf)
{
  const double *list = reinterpret_cast<const double *>(buf);
  const int values = list[0] == kRestartFormat ? V_SIZE
                     : list[0] == 7.0          ? V_RESTARTS
                     : list[0] == 6.0          ? V_SPLIT
                     : list[0] == 5.0          ? V_SUBSTEPS
                     : list[0] == 4.0          ? V_CHECK_VELOCITY
                     : list[0] == 3.0          ? V_WALL_WORK
                     : list[0] == 2.0          ? V_ERROR_ESTIMATE
                                               : 0;
  if (values == 0) {
    warn(error, FLERR, std::string("Fix fibre_contact: restart data of another format ignored"));
    return;
  }
  nonconverged_total_ = static_cast<bigint>(list[1]);
  for (int k = 0; k < values; ++k) stats_[k] = list[2 + k];
}

double FibreOutput::memory_bytes() const
{
  return double(maxlocal_) * kLocalColumns * sizeof(double);
}

} // namespace fibre_lmp
