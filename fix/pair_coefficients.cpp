#include "pair_coefficients.h"

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "atom.h"
#include "fibre/text.hpp"
#include "force.h"
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

void read_granular(const std::string &bytes, int ntypes, PairReading &out)
{
  Record rec(bytes);
  fibre::MaterialTable table(ntypes);
  bool cohesion = false;
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
      fibre::PairCoefficients &p = table.at(i, j);
      p.set = true;
      p.mu = tangential[2];
      p.mu_roll = model[3] == 1 ? roll[2] : 0.0;
      p.twist = model[4] == 1   ? fibre::TwistLaw::sds
                : model[4] == 2 ? fibre::TwistLaw::marshall
                                : fibre::TwistLaw::none;
      p.twist_coeff = model[4] == 1 ? twist[2] : 0.0;
      p.limit_damping = model[5] != 0;
      // elastic laws (compliance material); dmt's elastic part is hertz/material's, jkr's
      // stored constants are not the Hertz ones
      const fibre::NormalLaw laws[5] = {fibre::NormalLaw::hooke, fibre::NormalLaw::hertz,
                                        fibre::NormalLaw::hertz_material,
                                        fibre::NormalLaw::hertz_material, fibre::NormalLaw::none};
      p.normal = laws[model[0]];
      p.k_n = normal[0];
      p.tangential = model[2] == 0   ? fibre::TangentialLaw::none
                     : model[2] == 1 ? fibre::TangentialLaw::linear
                                     : fibre::TangentialLaw::mindlin;
      p.k_t = tangential[0];
      p.k_roll = model[3] == 1 ? roll[0] : 0.0;
      p.k_twist = model[4] == 1 ? twist[0] : 0.0;
      p.gamma_roll = model[3] == 1 ? roll[1] : 0.0;
      p.gamma_twist = model[4] == 1 ? twist[1] : 0.0;
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
      cohesion = cohesion || model[0] == kDmt || model[0] == kJkr;
      if (model[1] != kTsuji)
        out.notes.push_back("types " + std::to_string(i) + " " + std::to_string(j) + ": damping " +
                            kDamping[model[1]] +
                            " has no single coefficient of restitution: the contacts are "
                            "plastic unless the fix's restitution keyword is given");
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
                      "by implicit Euler; the tangential rows take the normal law's or its "
                      "critical damping, whichever is longer; bounces take e); the tangential "
                      "damping coefficient is not used");
  if (cohesion) out.notes.push_back("the cohesion of dmt and jkr is not modelled");
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
  rec.next_double(); // gammat
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
    }
  out.notes.push_back("pair style " + style + ": mu = xmu " + fibre::format_g(xmu) + "; kn " +
                      fibre::format_g(kn) + ", kt " + fibre::format_g(kt) +
                      " are used by 'compliance material' only (the default here is 'compliance "
                      "auto', rigid rows: kn = 1 is the common neighbour-list-only setting), and "
                      "its damping gamman " +
                      fibre::format_g(gamman) +
                      " is viscous, without a single coefficient of restitution: the contacts "
                      "are plastic unless the fix's restitution keyword is given");
  out.table = std::move(table);
}

} // namespace

PairReading read_pair_coefficients(LAMMPS_NS::LAMMPS *lmp)
{
  PairReading out;
  LAMMPS_NS::Pair *pair = lmp->force->pair;
  const std::string style = lmp->force->pair_style ? lmp->force->pair_style : "";
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
