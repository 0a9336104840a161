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
  // Solve the contacts every N steps, each solve over the N steps to the next (its impulses
  // applied at once, the external forces every step); 0: auto (steps_per_solve).
  int contact_every = 1;
  // Clumps: the spheres of one molecule (a nonzero molecule ID) move as one rigid body, held by
  // lock joints (joint_contact); contacts within a clump are not detected.
  bool clumps = false;
  // For the log: typed tuning keywords that have no effect under these settings, and
  // deprecated ones.
  std::vector<std::string> notes;
};

// contact_every auto's solve step, in collision times: LAMMPS's pour flow (shortened) keeps its
// kinetic energy 6.5% below native's at 0.14 t_c (every step: 5%), 13% below at 0.31 t_c.
inline constexpr double kEveryCollisions = 1.0 / 6.0;

// A solve over several steps (contact_every) in a deck with moving walls is split in substeps
// of at most this many collision times: in one of t_c / 6, LAMMPS's mixer threw grains off its
// blades to a height of 15.7 +- 3.3 over five seeds (native 11.5 +- 0.7), in two of t_c / 12
// still to 17.8 and 18.6 in two seeds, in four of t_c / 24 (from the first solve that met a
// blade) to 10.6 +- 1.6, at 20% more time than one. Without moving walls, substeps left the
// pour's flow as it was.
inline constexpr double kEveryMovingCollisions = 1.0 / 24.0;

// contact_every auto's steps a solve at step dt: the most whose sum is at most
// kEveryCollisions t_c, at least 1 (1 without a collision time).
int steps_per_solve(double t_c, double dt);

// The two tiers of keywords: what a DEM deck sets, and the solver's tuning.
enum class KeywordTier { user, tuning };

// One keyword of the table that drives the parser, its error messages and the doc page's
// Syntax (a test checks that the page lists the same names in the same tiers).
struct KeywordInfo {
  std::string name;
  KeywordTier tier;
  std::string expected; // the form an error message names: 'tol none|<positive number>'
  std::string help;     // one line
};

// Every keyword, the user tier first.
std::vector<KeywordInfo> keywords();

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
