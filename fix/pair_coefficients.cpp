#include "pair_coefficients.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "atom.h"
#include "fibre/core/text.hpp"
#include "force.h"
#include "host.h"
#include "lammps.h"
#include "pair.h"

namespace fibre_lmp {

namespace {

// The pair style's restart record in memory.
std::string restart_record(LAMMPS_NS::Pair *pair)
{
  char *buf = nullptr;
  std::size_t size = 0;
  FILE *fp = open_memstream(&buf, &size);
  if (!fp) return "";
  pair->write_restart(fp);
  std::fclose(fp);
  std::string out(buf, size);
  std::free(buf);
  return out;
}

// Reads ints and doubles in order; ok() turns false at the first read past the end.
class Record {
 public:
  explicit Record(const std::string &bytes) : bytes_(bytes) {}
  int next_int() { return next<int>(); }
  double next_double() { return next<double>(); }
  bool ok() const { return ok_; }
  bool at_end() const { return at_ == bytes_.size(); }

 private:
  template <class T> T next()
  {
    T v{};
    if (at_ + sizeof(T) > bytes_.size()) {
      ok_ = false;
      return v;
    }
    std::memcpy(&v, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  const std::string &bytes_;
  std::size_t at_ = 0;
  bool ok_ = true;
};

// Model codes of pair_style granular, LAMMPS 29 Sep 2021.
const char *const kDamping[] = {"velocity", "mass_velocity", "viscoelastic", "tsuji"};
constexpr int kTsuji = 3, kDmt = 3, kJkr = 4;
constexpr int kTangentialModels = 6;

// One type pair of pair style granular's record: its model indices (normal, damping,
// tangential, rolling, twisting, limit_damping) and the coefficients of each sub-model.
void set_granular(const int *model, const double *normal, const double *tangential,
                  const double *roll, const double *twist, fibre::PairCoefficients &p)
{
  p.set = true;
  p.mu = tangential[2];
  p.mu_roll = model[3] == 1 ? roll[2] : 0.0;
  p.twist = model[4] == 1   ? fibre::TwistLaw::sds
            : model[4] == 2 ? fibre::TwistLaw::marshall
                            : fibre::TwistLaw::none;
  p.twist_coeff = model[4] == 1 ? twist[2] : 0.0;
  p.limit_damping = model[5] != 0;
  // elastic laws (compliance material); dmt's and jkr's elastic part is hertz/material's
  // (LAMMPS stores 4/3 E_eff for all three)
  const fibre::NormalLaw laws[5] = {
      fibre::NormalLaw::hooke, fibre::NormalLaw::hertz, fibre::NormalLaw::hertz_material,
      fibre::NormalLaw::hertz_material, fibre::NormalLaw::hertz_material};
  p.normal = laws[model[0]];
  p.k_n = normal[0];
  p.tangential = model[2] == 0   ? fibre::TangentialLaw::none
                 : model[2] == 1 ? fibre::TangentialLaw::linear
                                 : fibre::TangentialLaw::mindlin;
  p.k_t = tangential[0];
  p.tangential_damping = tangential[1]; // x_gamma_t: its dashpot over the normal one
  p.k_roll = model[3] == 1 ? roll[0] : 0.0;
  p.k_twist = model[4] == 1 ? twist[0] : 0.0;
  p.gamma_roll = model[3] == 1 ? roll[1] : 0.0;
  p.gamma_twist = model[4] == 1 ? twist[1] : 0.0;
  // dmt's and jkr's surface energy gamma
  if (model[0] == kDmt || model[0] == kJkr) {
    p.cohesion = model[0] == kJkr ? fibre::CohesionLaw::jkr : fibre::CohesionLaw::dmt;
    p.cohesion_energy = normal[3];
  }
  // the rebound LAMMPS's own law gives (dmt and jkr: their Hertz part)
  if (model[1] == kTsuji) {
    p.damping_alpha = normal[1];
    p.restitution = fibre::rebound_restitution(model[0] == 0 ? fibre::NormalLaw::hooke
                                                             : fibre::NormalLaw::hertz,
                                               normal[1], p.limit_damping);
  }
  // the viscous models' dashpots (velocity, mass_velocity, viscoelastic: 0, 1, 2)
  if (model[1] != kTsuji) {
    const fibre::ViscousDamping viscous[3] = {fibre::ViscousDamping::velocity,
                                              fibre::ViscousDamping::mass_velocity,
                                              fibre::ViscousDamping::viscoelastic};
    p.viscous = viscous[model[1]];
    p.viscous_coeff = normal[1];
  }
}

void read_granular(const std::string &bytes, int ntypes, PairReading &out)
{
  Record rec(bytes);
  fibre::MaterialTable table(ntypes);
  for (int i = 1; i <= ntypes; ++i)
    for (int j = i; j <= ntypes; ++j) {
      if (!rec.next_int()) continue; // setflag: mixed at init
      int model[6];
      for (int &m : model) m = rec.next_int();
      double normal[4], tangential[3], roll[3], twist[3];
      for (double &v : normal) v = rec.next_double();
      for (double &v : tangential) v = rec.next_double();
      for (double &v : roll) v = rec.next_double();
      for (double &v : twist) v = rec.next_double();
      rec.next_double(); // cutoff
      if (!rec.ok() || model[0] < 0 || model[0] > 4 || model[1] < 0 || model[1] > 3 ||
          model[2] < 0 || model[2] >= kTangentialModels || model[3] < 0 || model[3] > 1 ||
          model[4] < 0 || model[4] > 2) {
        out.failure = "unexpected record of pair style granular (LAMMPS version layout)";
        return;
      }
      set_granular(model, normal, tangential, roll, twist, table.at(i, j));
      if (model[1] != kTsuji)
        out.notes.push_back("types " + std::to_string(i) + " " + std::to_string(j) + ": damping " +
                            kDamping[model[1]] +
                            " has no single coefficient of restitution: each impact rebounds "
                            "as the law's spring and dashpot give for its masses, radii and "
                            "approach speed (unless the fix's restitution keyword is given)");
    }
  if (!rec.ok() || !rec.at_end()) {
    out.failure = "unexpected length of pair style granular's record (LAMMPS version layout)";
    return;
  }
  const std::string mixed = table.mix();
  if (!mixed.empty()) {
    out.failure = mixed;
    return;
  }
  out.notes.push_back("the stiffnesses of pair_coeff (normal, tangential, rolling and twisting "
                      "sds) set the rows' compliance ('compliance material', the default here; "
                      "'compliance auto' makes the rows rigid), and the normal, rolling and "
                      "twisting dampers their rows' damping, at least SPOOK's (with "
                      "'normal_relaxation law' the normal row is the law's spring and dashpot "
                      "by implicit Euler; at steps of at most 0.1 collision times the "
                      "tangential rows take the law's tangential dashpot, x_gamma_t times the "
                      "normal one; bounces take e)");
  out.table = std::move(table);
  out.material = true;
}

// gran/hooke, gran/hooke/history, gran/hertz/history: kn kt gamman gammat xmu (doubles),
// dampflag (int), then setflag per type pair.
void read_gran(const std::string &style, const std::string &bytes, int ntypes, PairReading &out)
{
  const bool hertz = style == "gran/hertz/history", history = style != "gran/hooke";
  Record rec(bytes);
  const double kn = rec.next_double(), kt = rec.next_double(), gamman = rec.next_double();
  const double gammat = rec.next_double(); // NULL and dampflag 0 are resolved in it
  const double xmu = rec.next_double();
  rec.next_int(); // dampflag
  for (int k = 0; k < ntypes * (ntypes + 1) / 2; ++k) rec.next_int();
  if (!rec.ok() || !rec.at_end() || !(xmu >= 0)) {
    out.failure = "unexpected record of pair style " + style;
    return;
  }
  fibre::MaterialTable table(ntypes);
  for (int i = 1; i <= ntypes; ++i)
    for (int j = i; j <= ntypes; ++j) {
      fibre::PairCoefficients &p = table.at(i, j);
      p.set = true;
      p.mu = xmu;
      p.normal = hertz ? fibre::NormalLaw::hertz : fibre::NormalLaw::hooke;
      p.k_n = kn;
      // the tangential spring (history styles) is scaled like the normal one
      p.tangential = !history ? fibre::TangentialLaw::none
                     : hertz  ? fibre::TangentialLaw::mindlin
                              : fibre::TangentialLaw::linear;
      p.k_t = kt;
      // the dashpot m_eff gamman (hooke), m_eff gamman a (hertz): compliance material's
      if (gamman > 0) {
        p.viscous =
            hertz ? fibre::ViscousDamping::viscoelastic : fibre::ViscousDamping::mass_velocity;
        p.viscous_coeff = gamman;
        p.tangential_damping = gammat / gamman;
      }
    }
  out.notes.push_back("pair style " + style + ": mu = xmu " + fibre::format_g(xmu) + "; kn " +
                      fibre::format_g(kn) + ", kt " + fibre::format_g(kt) +
                      " are used by 'compliance material' only (the default here is 'compliance "
                      "auto', rigid rows: kn = 1 is the common neighbour-list-only setting), and "
                      "its damping gamman " +
                      fibre::format_g(gamman) +
                      " is viscous, without a single coefficient of restitution: under "
                      "'compliance material' each impact rebounds as the law's spring and "
                      "dashpot give for its masses, radii and approach speed; otherwise the "
                      "contacts are plastic unless the fix's restitution keyword is given");
  out.table = std::move(table);
}

// Reads words[k], words[k+1], ... as numbers; false at the first that is missing or not one.
bool numbers(const std::vector<std::string> &words, std::size_t k, std::size_t n, double *out)
{
  for (std::size_t m = 0; m < n; ++m)
    if (k + m >= words.size() || !fibre::to_double(words[k + m], out[m])) return false;
  return true;
}

// fix wall/gran's hooke, hooke/history and hertz/history: kn kt gamman gammat xmu dampflag
// (kt NULL: 2/7 kn); gamman is a viscous dashpot, m gamman (hooke) or m gamman a (hertz).
void read_wall_gran(const std::vector<std::string> &words, WallReading &out)
{
  const std::string &style = words[0];
  const bool hertz = style == "hertz/history";
  double v[6] = {0, 0, 0, 0, 0, 0};
  const bool kt_null = words.size() > 2 && words[2] == "NULL";
  std::vector<std::string> w = words;
  if (kt_null) w[2] = "0";
  if (w.size() > 4 && w[4] == "NULL") w[4] = "0";
  if (w.size() != 7 || !numbers(w, 1, 6, v) || v[0] < 0 || v[1] < 0 || v[2] < 0 || v[4] < 0) {
    out.failure = "expected '" + style + " <kn> <kt|NULL> <gamman> <gammat|NULL> <xmu> <dampflag>'";
    return;
  }
  fibre::PairCoefficients &p = out.coefficients;
  p.set = true;
  p.normal = hertz ? fibre::NormalLaw::hertz : fibre::NormalLaw::hooke;
  p.k_n = v[0];
  p.tangential = style == "hooke" ? fibre::TangentialLaw::none
                 : hertz          ? fibre::TangentialLaw::mindlin
                                  : fibre::TangentialLaw::linear;
  p.k_t = kt_null ? v[0] * 2.0 / 7.0 : v[1];
  p.viscous = hertz ? fibre::ViscousDamping::viscoelastic : fibre::ViscousDamping::mass_velocity;
  p.viscous_coeff = v[2];
  p.mu = v[4];
  // fix wall/gran's gamma_t (NULL: gamma_n / 2), none with dampflag 0
  const double gammat = words[4] == "NULL" ? 0.5 * v[2] : v[3];
  if (v[2] > 0) p.tangential_damping = v[5] == 0 ? 0.0 : gammat / v[2];
}

// One model of fix wall/gran granular at words[k] (hooke, hertz, hertz/material, dmt, jkr,
// damping, tangential, rolling, twisting); returns the words read, 0 on a failure.
std::size_t read_granular_model(const std::vector<std::string> &words, std::size_t k,
                                WallReading &out, double &e_mod, double &nu, double &damp,
                                int &damping)
{
  fibre::PairCoefficients &p = out.coefficients;
  const std::string &m = words[k];
  const std::string next = k + 1 < words.size() ? words[k + 1] : "";
  double v[4] = {0, 0, 0, 0};
  if (m == "hooke" || m == "hertz") {
    if (!numbers(words, k + 1, 2, v)) return 0;
    p.normal = m == "hooke" ? fibre::NormalLaw::hooke : fibre::NormalLaw::hertz;
    p.k_n = v[0];
    damp = v[1];
    return 3;
  }
  if (m == "hertz/material" || m == "dmt" || m == "jkr") {
    const std::size_t n = m == "hertz/material" ? 3 : 4;
    if (!numbers(words, k + 1, n, v)) return 0;
    e_mod = v[0];
    damp = v[1];
    nu = v[2];
    // fix wall/gran's wall constant (not the pair's 4/3 E / (2 (1 - nu^2)))
    p.normal = fibre::NormalLaw::hertz_material;
    p.k_n = 4.0 / 3.0 * e_mod / (2.0 * (1.0 - nu));
    if (n == 4) { // the wall's cohesion, its surface energy gamma
      p.cohesion = m == "jkr" ? fibre::CohesionLaw::jkr : fibre::CohesionLaw::dmt;
      p.cohesion_energy = v[3];
    }
    return n + 1;
  }
  if (m == "damping") {
    const char *const models[] = {"velocity", "mass_velocity", "viscoelastic", "tsuji"};
    for (int d = 0; d < 4; ++d)
      if (next == models[d]) damping = d;
    return damping >= 0 && next == models[damping] ? 2 : 0;
  }
  if (m == "tangential") {
    if (next == "linear_nohistory") {
      if (!numbers(words, k + 2, 2, v)) return 0;
      p.tangential = fibre::TangentialLaw::none;
      p.mu = v[1];
      return 4;
    }
    if (next != "linear_history" && next != "mindlin" && next != "mindlin_rescale") return 0;
    const bool null = k + 2 < words.size() && words[k + 2] == "NULL" && next != "linear_history";
    if (!numbers(words, k + 3, 2, v + 1) || (!null && !numbers(words, k + 2, 1, v))) return 0;
    if (null && e_mod <= 0) {
      out.failure = "'tangential " + next + " NULL' needs hertz/material, dmt or jkr before it";
      return 0;
    }
    p.tangential =
        next == "linear_history" ? fibre::TangentialLaw::linear : fibre::TangentialLaw::mindlin;
    p.k_t = null ? e_mod / 4.0 * (2.0 - nu) * (1.0 + nu) : v[0]; // fix wall/gran's constant
    p.tangential_damping = v[1];                                 // x_gamma_t
    p.mu = v[2];
    return 5;
  }
  if ((m == "rolling" || m == "twisting") && next == "none") return 2;
  if (m == "twisting" && next == "marshall") {
    p.twist = fibre::TwistLaw::marshall;
    return 2;
  }
  if ((m == "rolling" || m == "twisting") && next == "sds") {
    if (!numbers(words, k + 2, 3, v)) return 0;
    if (m == "rolling") {
      p.k_roll = v[0];
      p.gamma_roll = v[1];
      p.mu_roll = v[2];
    } else {
      p.twist = fibre::TwistLaw::sds;
      p.k_twist = v[0];
      p.gamma_twist = v[1];
      p.twist_coeff = v[2];
    }
    return 5;
  }
  return 0;
}

void read_wall_granular(const std::vector<std::string> &words, WallReading &out)
{
  double e_mod = 0.0, nu = 0.0, damp = 0.0;
  int damping = 2; // viscoelastic, fix wall/gran's default
  std::size_t k = 1;
  while (k < words.size()) {
    const std::size_t used = read_granular_model(words, k, out, e_mod, nu, damp, damping);
    if (used == 0) {
      if (out.failure.empty())
        out.failure = "cannot read '" + words[k] +
                      "' and its arguments as fix wall/gran granular's (hooke, hertz, "
                      "hertz/material, dmt, jkr, damping, tangential, rolling, twisting)";
      return;
    }
    k += used;
  }
  fibre::PairCoefficients &p = out.coefficients;
  if (p.normal == fibre::NormalLaw::none) {
    out.failure = "'granular' needs a normal model (hooke, hertz, hertz/material, dmt or jkr)";
    return;
  }
  p.set = true;
  if (damping == kTsuji) {
    p.damping_alpha = fibre::tsuji_damping(damp);
    p.restitution = fibre::rebound_restitution(
        p.normal == fibre::NormalLaw::hooke ? fibre::NormalLaw::hooke : fibre::NormalLaw::hertz,
        p.damping_alpha);
  } else {
    const fibre::ViscousDamping viscous[3] = {fibre::ViscousDamping::velocity,
                                              fibre::ViscousDamping::mass_velocity,
                                              fibre::ViscousDamping::viscoelastic};
    p.viscous = viscous[damping];
    p.viscous_coeff = damp;
  }
}

} // namespace

WallReading read_wall_interaction(const std::vector<std::string> &words)
{
  WallReading out;
  const std::string style = words.empty() ? "" : words[0];
  if (style == "granular")
    read_wall_granular(words, out);
  else if (style == "hooke" || style == "hooke/history" || style == "hertz/history")
    read_wall_gran(words, out);
  else
    out.failure = "expected fix wall/gran's interaction: granular, hooke, hooke/history or "
                  "hertz/history";
  if (out.failure.empty() && out.coefficients.restitution < 0)
    out.notes.push_back("the wall's viscous damping has no single coefficient of restitution: "
                        "each impact rebounds as the law's spring and dashpot give for the "
                        "sphere's mass, radius and approach speed");
  return out;
}

PairReading read_pair_coefficients(LAMMPS_NS::LAMMPS *lmp)
{
  PairReading out;
  std::string style;
  LAMMPS_NS::Pair *pair = granular_pair(lmp, style);
  const int ntypes = lmp->atom->ntypes;
  if (!pair || ntypes < 1) {
    out.failure = "no pair style";
    return out;
  }
  const std::string bytes = restart_record(pair);
  if (style == "granular") {
    if (std::strcmp(lmp->version, "29 Sep 2021") != 0) {
      out.failure = std::string("the record of pair style granular is known for LAMMPS 29 Sep "
                                "2021 only, this is ") +
                    lmp->version;
      return out;
    }
    read_granular(bytes, ntypes, out);
  } else if (style == "gran/hooke" || style == "gran/hooke/history" ||
             style == "gran/hertz/history") {
    read_gran(style, bytes, ntypes, out);
  } else {
    out.failure = "pair style " + style + " has no coefficients the fix can read";
  }
  return out;
}

} // namespace fibre_lmp
