// Accuracy against cost of the step solver's settings on exported steps (doc/design.md
// section 4): a step state is what `fix fibre_contact export` writes (the system, the step's
// impulses and the warm start it began from); every setting replays the step from that warm
// start and is measured against the step's converged reference (nonsmooth_reference.hpp). Cost
// is counted in K-product equivalents: the solve's time over one body-form product's time,
// measured in the same run. Serial.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "fibre/step/step_solver.hpp"
#include "fibre/study/nonsmooth_reference.hpp"

namespace fibre {

struct StepState {
  ContactSystem sys;
  Vector lambda; // the impulses the run found (zero when the export has none)
  Vector warm;   // the warm start of the run's solve (zero when the export has none)
  // A serial periodic step's images (PREFIX.images): every local body's body; empty: none.
  std::shared_ptr<const ImageExchange> images;
  // the step's exchange: serial, with the images where it has them
  const Exchange &exchange() const { return images ? *images : serial_exchange(); }
};

// PREFIX.sys and PREFIX.lambda, and PREFIX.images where the run wrote one (doc/system_format.md,
// doc/fix_fibre_contact.md "Export").
// Throws std::runtime_error with the file and line of a problem.
StepState read_step_state(const std::string &prefix);

// The time of one product with K = M + G^T Sigma^-1 G (the median of `repeat`).
double k_product_seconds(const ContactSystem &sys, int repeat = 21);

struct StudyRow {
  std::string setting;
  double seconds = 0;    // the fastest of the repeats
  double k_products = 0; // seconds / k_product_seconds
  int iterations = 0, passes = 0, sweeps = 0;
  int slow_restarts = 0;        // StepResult::slow_restarts
  double sweep_equivalents = 0; // StepResult::sweep_equivalents
  double complementarity = 0;
  double error_estimate = 0; // StepResult::error_estimate
  bool converged = false;
  StepAccuracy error;
};

// Replays the step with `opt` from the state's warm start, `repeat` times.
StudyRow measure_setting(const StepState &state, const StepOptions &opt, const Vector &reference,
                         double k_seconds, int repeat = 3);

} // namespace fibre
