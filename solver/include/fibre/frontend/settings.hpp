// The settings of fix fibre_contact, shared by every front end: its keywords parsed into the
// step's options, the contact model, the walls and the export, with LAMMPS-style messages
// ("expected 'linear_tol <positive number>', got '-1'"). Defaults come from StepOptions{} and
// ContactModel{}: a keyword the user did not type leaves them as they are.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "fibre/geometry/detection.hpp"
#include "fibre/model/contact_model.hpp"
#include "fibre/step/step_solver.hpp"

namespace fibre {

struct Settings {
  StepOptions step{};
  ContactModel model{};
  std::vector<WallSpec> walls;
  int export_every = 0; // write the step's system every N steps (0: never)
  std::string export_prefix;
  int check_every = 0; // solve the step again converged every N steps (0: never)
};

// What follows "Illegal fix fibre_contact command: " in the front end's error.
class SettingsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The keywords after "fix ID group fibre_contact". Throws SettingsError.
Settings parse_settings(const std::vector<std::string> &args);

// One line for the log: the step's options (describe(StepOptions)), rows, damping, the
// compliance rule and the friction coefficients.
std::string describe(const Settings &s);

} // namespace fibre
