// The material of a LIGGGHTS deck per type pair, for fix fibre_contact (the LIGGGHTS side of
// fix/pair_coefficients.h): fix property/global tables and the models chosen in
// `pair_style gran model M tangential T rolling_friction R`.
//
//   coefficientFriction peratomtypepair        -> mu
//   coefficientRestitution peratomtypepair     -> restitution (Newton's e)
//   coefficientRollingFriction peratomtypepair -> mu_roll, with rolling_friction cdt or epsd*
//   youngsModulus, poissonsRatio peratomtype   -> model hertz: k_n = 4/3 Y*, k_t = 8 G*
//     (1/Y* = (1 - nu_i^2)/Y_i + (1 - nu_j^2)/Y_j, 1/G* = 2 (2 - nu_i)(1 + nu_i)/Y_i + ...),
//     the laws LIGGGHTS's hertz and tangential history apply; `compliance material` uses them,
//     with hertz's dashpots (their rebound is coefficientRestitution).
//   cohesionEnergyDensity peratomtypepair      -> cohesion sjkr's k_c (with model hertz)
// Mesh walls have a type of their own (fix mesh/surface ... type T), so a wall contact takes
// the pair (sphere type, T) as native LIGGGHTS does.
#include <cmath>
#include <string>

#include "atom.h"
#include "fix_property_global.h"
#include "force.h"
#include "lammps.h"
#include "modify.h"
#include "pair_coefficients.h"
#include "pair_gran.h"

namespace fibre_lmp {

namespace {

// The fix property/global that registers `name`, or nullptr; `shape` peratomtype or
// peratomtypepair over every atom type (mesh types included). A table of another shape is an
// error that names it.
LAMMPS_NS::FixPropertyGlobal *property(LAMMPS_NS::LAMMPS *lmp, const char *name, const char *shape,
                                       std::string &failure)
{
  const int ntypes = lmp->atom->ntypes;
  const bool pairs = std::string(shape) == "peratomtypepair";
  for (int i = 0; i < lmp->modify->nfix; ++i) {
    LAMMPS_NS::Fix *fix = lmp->modify->fix[i];
    if (std::string(fix->style) != "property/global") continue;
    auto *table = static_cast<LAMMPS_NS::FixPropertyGlobal *>(fix);
    if (!table->check_fix(name, "", 0, 0, "fix fibre_contact", false)) continue;
    if (table->check_fix(name, shape, ntypes, pairs ? ntypes : 0, "fix fibre_contact", false))
      return table;
    failure = std::string("fix property/global ") + name + " must be '" + shape + "' with " +
              (pairs ? std::to_string(ntypes) + " x " : std::string()) + std::to_string(ntypes) +
              " values";
    return nullptr;
  }
  return nullptr;
}

// The value of a scalar fix property/global `name` (LIGGGHTS's characteristicVelocity), or 0.
double scalar_property(LAMMPS_NS::LAMMPS *lmp, const char *name)
{
  for (int i = 0; i < lmp->modify->nfix; ++i) {
    LAMMPS_NS::Fix *fix = lmp->modify->fix[i];
    if (std::string(fix->style) != "property/global") continue;
    auto *table = static_cast<LAMMPS_NS::FixPropertyGlobal *>(fix);
    if (table->check_fix(name, "scalar", 0, 0, "fix fibre_contact", false))
      return table->compute_scalar();
  }
  return 0.0;
}

bool matches(LAMMPS_NS::PairGran *pair, const char *kind, const char *model)
{
  return pair && pair->contact_match(kind, model);
}

// LIGGGHTS's hooke for type pair (i, j): Y_eff and the characteristicVelocity give each
// contact its k_n and k_t = k_n (fibre::contact_law); the dashpot sqrt(4 m_eff k_n / (1 + (pi /
// ln e)^2)) is alpha sqrt(m_eff k_n) with alpha = 2 |ln e| / sqrt(ln^2 e + pi^2). Its
// tangential dashpot (tangential_damping on, the default) is the normal one.
void set_hooke(double y_eff, double v_char, bool history, fibre::PairCoefficients &p)
{
  p.normal = fibre::NormalLaw::hooke;
  p.hooke_y_eff = y_eff;
  p.hooke_velocity = v_char;
  if (history) p.tangential = fibre::TangentialLaw::linear;
  p.tangential_damping = 1.0;
  p.cone_on_spring = true;
  const double e = p.restitution;
  if (e > 0 && e <= 1) p.damping_alpha = fibre::liggghts_hooke_damping(e);
}

// LIGGGHTS's hertz with tangential history: k_n = 4/3 Y_eff, Mindlin's k_t = 8 G_eff, and its
// normal dashpot for the pair's restitution. Its tangential dashpot (tangential_damping on, the
// default) is the normal one times sqrt(S_t / S_n), S_t = 8 G_eff a and S_n = 2 Y_eff a.
void set_hertz(double y_eff, double g_eff, bool history, fibre::PairCoefficients &p)
{
  p.normal = fibre::NormalLaw::hertz_material;
  p.k_n = 4.0 / 3.0 * y_eff;
  if (history) {
    p.tangential = fibre::TangentialLaw::mindlin;
    p.k_t = 8.0 * g_eff;
  }
  if (y_eff > 0) p.tangential_damping = 2.0 * std::sqrt(g_eff / y_eff);
  p.cone_on_spring = true;
  const double e = p.restitution;
  if (e > 0 && e <= 1) p.damping_alpha = fibre::liggghts_hertz_damping(e);
}

// The pair style's cohesion: sjkr's cohesionEnergyDensity table (nullptr without sjkr, or on
// a failure), and a WARNING for each cohesion model the fix does not carry.
LAMMPS_NS::FixPropertyGlobal *read_cohesion(LAMMPS_NS::LAMMPS *lmp, LAMMPS_NS::PairGran *pair,
                                            bool hertz, PairReading &out)
{
  for (const char *model : {"sjkr2", "easo/capillary/viscous", "washino/capillary/viscous"})
    if (matches(pair, "cohesion", model))
      out.warnings.push_back(std::string("pair style gran's 'cohesion ") + model +
                             "' is not modelled: the contacts have no cohesion (keep such a "
                             "deck native, or accept cohesionless grains)");
  // LIGGGHTS's walls name their own models: the converted walls take the type's without cohesion
  out.wall_cohesion = false;
  if (!matches(pair, "cohesion", "sjkr")) return nullptr;
  auto *table = property(lmp, "cohesionEnergyDensity", "peratomtypepair", out.failure);
  if (!table && out.failure.empty())
    out.failure = "cohesion sjkr needs 'fix ID all property/global cohesionEnergyDensity "
                  "peratomtypepair " +
                  std::to_string(lmp->atom->ntypes) + " ...'";
  out.notes.push_back("cohesion sjkr acts between grains; walls take their type's material "
                      "without it (as fix wall/gran without 'cohesion sjkr')");
  if (!hertz)
    out.warnings.push_back("pair style gran's 'cohesion sjkr' is modelled on model hertz only: "
                           "these contacts have no cohesion");
  return out.failure.empty() ? table : nullptr;
}

} // namespace

PairReading read_pair_coefficients(LAMMPS_NS::LAMMPS *lmp)
{
  PairReading out;
  out.required = true;
  const int ntypes = lmp->atom->ntypes;
  auto *pair = dynamic_cast<LAMMPS_NS::PairGran *>(lmp->force->pair);
  if (!pair || ntypes < 1) {
    out.failure = "no pair style gran";
    return out;
  }
  auto *friction = property(lmp, "coefficientFriction", "peratomtypepair", out.failure);
  auto *restitution = property(lmp, "coefficientRestitution", "peratomtypepair", out.failure);
  auto *rolling = property(lmp, "coefficientRollingFriction", "peratomtypepair", out.failure);
  auto *young = property(lmp, "youngsModulus", "peratomtype", out.failure);
  auto *poisson = property(lmp, "poissonsRatio", "peratomtype", out.failure);
  if (!out.failure.empty()) return out;
  if (!friction) {
    out.failure = "no 'fix ID all property/global coefficientFriction peratomtypepair " +
                  std::to_string(ntypes) + " ...'";
    return out;
  }
  const bool cdt =
      matches(pair, "rolling_friction", "cdt") || matches(pair, "rolling_friction", "epsd") ||
      matches(pair, "rolling_friction", "epsd2") || matches(pair, "rolling_friction", "epsd3");
  const bool hertz = matches(pair, "normal", "hertz");
  const bool history = matches(pair, "tangential", "history");
  if (rolling && !cdt)
    out.notes.push_back("coefficientRollingFriction is not used: the pair style has no "
                        "rolling_friction model (as in native LIGGGHTS)");
  if (cdt && !rolling) {
    out.failure = "rolling_friction needs 'fix ID all property/global coefficientRollingFriction "
                  "peratomtypepair " +
                  std::to_string(ntypes) + " ...'";
    return out;
  }
  LAMMPS_NS::FixPropertyGlobal *cohesion = read_cohesion(lmp, pair, hertz, out);
  if (!out.failure.empty()) return out;
  const bool hooke = matches(pair, "normal", "hooke");
  const double v_char = hooke ? scalar_property(lmp, "characteristicVelocity") : 0.0;
  if (!hertz && !(hooke && v_char > 0))
    out.notes.push_back(
        "the normal model is neither hertz nor hooke with a characteristicVelocity: "
        "compliance material has no elastic constants here; the rows stay rigid");
  if (!restitution)
    out.notes.push_back("no coefficientRestitution: contacts are plastic unless the fix's "
                        "restitution keyword is given");
  if (hertz || hooke)
    out.notes.push_back("at steps of at most 0.1 collision times the tangential springs take "
                        "the model's tangential dashpot as 'tangential_damping on' (its default) "
                        "gives it; 'tangential_damping off' is not read");

  fibre::MaterialTable table(ntypes);
  for (int i = 1; i <= ntypes; ++i)
    for (int j = i; j <= ntypes; ++j) {
      fibre::PairCoefficients &p = table.at(i, j);
      p.set = true;
      p.mu = friction->compute_array(i - 1, j - 1);
      if (cdt) p.mu_roll = rolling->compute_array(i - 1, j - 1);
      if (restitution) p.restitution = restitution->compute_array(i - 1, j - 1);
      if (!young || !poisson) continue;
      const double yi = young->compute_vector(i - 1), yj = young->compute_vector(j - 1);
      const double ni = poisson->compute_vector(i - 1), nj = poisson->compute_vector(j - 1);
      const double y_eff = 1.0 / ((1.0 - ni * ni) / yi + (1.0 - nj * nj) / yj);
      if (hertz) {
        const double g_eff =
            1.0 / (2.0 * (2.0 - ni) * (1.0 + ni) / yi + 2.0 * (2.0 - nj) * (1.0 + nj) / yj);
        set_hertz(y_eff, g_eff, history, p);
        if (cohesion) { // F = F_H - k_c A (fibre/model/cohesion.hpp)
          p.cohesion = fibre::CohesionLaw::sjkr;
          p.cohesion_energy = cohesion->compute_array(i - 1, j - 1);
        }
      }
      if (hooke && v_char > 0) set_hooke(y_eff, v_char, history, p);
    }
  out.table = std::move(table);
  out.material = (hertz || (hooke && v_char > 0)) && young && poisson;
  return out;
}

} // namespace fibre_lmp

namespace fibre_lmp {

// LIGGGHTS walls take a type's material (fix wall/gran's `primitive type T`, a mesh's type):
// fix wall/gran's LAMMPS interaction words are LAMMPS's.
WallReading read_wall_interaction(const std::vector<std::string> &words)
{
  WallReading out;
  out.failure = "'" + (words.empty() ? std::string() : words[0]) +
                "' is LAMMPS's fix wall/gran interaction; a LIGGGHTS wall takes the material of "
                "an atom type from fix property/global: 'wall type <T> ...' (as fix wall/gran's "
                "'primitive type T')";
  return out;
}

} // namespace fibre_lmp
