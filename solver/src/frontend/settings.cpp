#include "fibre/frontend/settings.hpp"

#include <algorithm>
#include <cmath>

#include "fibre/core/text.hpp"
#include "fibre/step/substeps.hpp"

namespace fibre {

namespace {

// Reads keyword values from args; every failure names the keyword's expected form.
class Reader {
 public:
  explicit Reader(const std::vector<std::string> &args) : args_(args) {}

  bool has(std::size_t i) const { return i < args_.size(); }
  const std::string &at(std::size_t i) const { return args_[i]; }

  [[noreturn]] static void illegal(const std::string &expected, const std::string *got = nullptr)
  {
    std::string msg = "expected " + expected;
    if (got) msg += ", got '" + *got + "'";
    throw SettingsError(msg);
  }

  double number(std::size_t i, const std::string &expected) const
  {
    if (!has(i)) illegal(expected);
    double value = 0.0;
    if (!to_double(args_[i], value)) illegal(expected, &args_[i]);
    return value;
  }

  double positive(std::size_t i, const std::string &expected) const
  {
    const double value = number(i, expected);
    if (!(value > 0.0)) illegal(expected, &args_[i]);
    return value;
  }

  long integer(std::size_t i, const std::string &expected, long lo, long hi) const
  {
    if (!has(i)) illegal(expected);
    long value = 0;
    if (!to_long(args_[i], value) || value < lo || value > hi) illegal(expected, &args_[i]);
    return value;
  }

  // yes or no, as `key yes|no`
  bool yes_no(std::size_t i, const std::string &key) const
  {
    const std::string expected = "'" + key + " yes|no'";
    if (!has(i) || (args_[i] != "yes" && args_[i] != "no"))
      illegal(expected, has(i) ? &args_[i] : nullptr);
    return args_[i] == "yes";
  }

  template <class E> E name(std::size_t i, const std::string &key) const
  {
    const std::string expected = "'" + key + " " + choices<E>() + "'";
    if (!has(i)) illegal(expected);
    E value{};
    if (!parse(args_[i], value)) illegal(expected, &args_[i]);
    return value;
  }

 private:
  const std::vector<std::string> &args_;
};

// Optional motion after a plane wall: "wiggle x|y|z <amplitude> <period>" or
// "shear x|y|z <speed>" (fix wall/gran's keywords); returns the words read.
std::size_t read_plane_motion(const Reader &in, std::size_t i, WallSpec &w)
{
  if (!in.has(i) || (in.at(i) != "wiggle" && in.at(i) != "shear")) return 0;
  const bool wiggle = in.at(i) == "wiggle";
  const std::string e = wiggle ? "'wiggle x|y|z <amplitude> <period>' (period > 0)"
                               : "'shear x|y|z <speed>' (x, y or z in the wall's plane)";
  if (!in.has(i + 1)) Reader::illegal(e);
  const std::string &axis = in.at(i + 1);
  if (axis != "x" && axis != "y" && axis != "z") Reader::illegal(e, &axis);
  w.motion_axis = axis[0] - 'x';
  if (wiggle) {
    w.motion = WallMotion::wiggle;
    w.amplitude = in.number(i + 2, e);
    w.period = in.positive(i + 3, e);
    return 4;
  }
  w.motion = WallMotion::shear;
  if (w.motion_axis == w.axis()) Reader::illegal(e, &axis);
  w.shear_speed = in.number(i + 2, e);
  return 3;
}

// "wall <material> x|y|zcylinder <radius> [<c1> <c2>]" from args[i] ("wall"): the grains are
// inside; the axis passes through c1 c2 in the other coordinates (0 0 if not given, as fix
// wall/gran's zcylinder; LIGGGHTS's primitive gives them).
std::size_t read_cylinder(const Reader &in, std::size_t i, WallSpec &w)
{
  const std::string kind = in.at(i + 1);
  const std::string e = "'wall " + kind + " <radius> [<c1> <c2>]' (radius > 0)";
  w.radius = in.positive(i + 2, e);
  std::size_t used = 3;
  double c[2] = {0.0, 0.0};
  if (in.has(i + 4) && to_double(in.at(i + 3), c[0]) && to_double(in.at(i + 4), c[1])) {
    w.centre[0] = c[0];
    w.centre[1] = c[1];
    used = 5;
  }
  if (in.has(i + used) && (in.at(i + used) == "wiggle" || in.at(i + used) == "shear"))
    Reader::illegal(e + " without motion (a cylinder wall stands still)", &in.at(i + used));
  return used;
}

// The wall's material before its style: "type <T>" or the interaction words of fix wall/gran
// (granular, hooke, hooke/history or hertz/history and their arguments, up to the style).
// Returns the words read.
std::size_t read_wall_material(const Reader &in, std::size_t i, WallSpec &w)
{
  if (!in.has(i)) return 0;
  const std::string &first = in.at(i);
  if (first == "type") {
    w.type = static_cast<int>(
        in.integer(i + 1, "'wall type <T> <style> ...' (T an atom type)", 1, 1000000));
    return 2;
  }
  if (first != "granular" && first != "hooke" && first != "hooke/history" &&
      first != "hertz/history")
    return 0;
  std::size_t k = i;
  WallKind kind{};
  while (in.has(k) && !parse(in.at(k), kind)) w.model.push_back(in.at(k++));
  if (!in.has(k))
    Reader::illegal("'wall " + first +
                    " <coefficients> xplane|yplane|zplane|zcylinder|region ...' (fix "
                    "wall/gran's "
                    "interaction and arguments, then the wall's style)");
  return k - i;
}

// "wall [type T | <fix wall/gran interaction>] xplane|yplane|zplane <lo|NULL> <hi|NULL>",
// "... region <region-ID>" or "... mesh <fix-ID>" at args[i]; returns the number of words read.
std::size_t read_wall(const Reader &in, std::size_t i, WallSpec &w)
{
  const std::string e =
      "'wall xplane|yplane|zplane <lo|NULL> <hi|NULL>', 'wall xcylinder|ycylinder|zcylinder "
      "<radius> [<c1> <c2>]', 'wall region <region-ID>' or 'wall mesh <fix-ID>' (optionally "
      "'type <T>' or fix wall/gran's interaction after 'wall')";
  const std::size_t material = read_wall_material(in, i + 1, w);
  if (material > 0) return material + read_wall(in, i + material, w);
  if (!in.has(i + 1)) Reader::illegal(e);
  const std::string &kind = in.at(i + 1);
  if (!parse(kind, w.kind)) Reader::illegal(e, &kind);
  if (w.is_cylinder()) return read_cylinder(in, i, w);
  if (!w.is_plane()) {
    const std::string ek = w.kind == WallKind::region ? "'wall region <region-ID>'"
                                                      : "'wall mesh <fix-ID>' (a fix mesh/surface)";
    if (!in.has(i + 2)) Reader::illegal(ek);
    w.id = in.at(i + 2);
    return 3;
  }
  const std::string ep = "'wall " + kind + " <lo|NULL> <hi|NULL>'";
  if (!in.has(i + 3)) Reader::illegal(ep);
  const std::string &lo = in.at(i + 2), &hi = in.at(i + 3);
  if (lo != "NULL") {
    if (!to_double(lo, w.lo)) Reader::illegal(ep, &lo);
    w.has_lo = true;
  }
  if (hi != "NULL") {
    if (!to_double(hi, w.hi)) Reader::illegal(ep, &hi);
    w.has_hi = true;
  }
  if (!w.has_lo && !w.has_hi) Reader::illegal(ep + " with at least one of lo and hi a number");
  const std::string both = lo + " " + hi;
  if (w.has_lo && w.has_hi && !(w.lo < w.hi)) Reader::illegal(ep + " with lo < hi", &both);
  return 4 + read_plane_motion(in, i + 4, w);
}

// What the readers of the keyword table share: the settings, and what the user typed.
struct ParseState {
  Settings &s;
  bool sweeps_typed = false;
  bool anderson_typed = false;
};

// Reads keyword args[i] (its expected form given); returns the words read.
using ReadKeyword = std::size_t (*)(const Reader &in, std::size_t i, const std::string &expected,
                                    ParseState &st);
// True where a typed tuning keyword has no effect under these settings.
using Inert = bool (*)(const Settings &s);

struct Keyword {
  KeywordInfo info;
  ReadKeyword read;
  Inert inert = nullptr;
  const char *inert_why = ""; // "no effect <why>" in the log
};

bool linear_pass(const Settings &s)
{
  const Method m = s.step.solver;
  return !(m == Method::pgs || m == Method::nncg || m == Method::fbgs || m == Method::apgd);
}

bool sweeps_only(const Settings &s)
{
  return !linear_pass(s);
}

std::string quoted(const std::string &key, const std::string &form)
{
  return "'" + key + " " + form + "'";
}

template <class E> std::string enum_form(const std::string &key)
{
  return quoted(key, choices<E>());
}

double non_negative(const Reader &in, std::size_t i, const std::string &e)
{
  const double v = in.number(i, e);
  if (!(v >= 0.0)) Reader::illegal(e, &in.at(i));
  return v;
}

int count(const Reader &in, std::size_t i, const std::string &e, long lo, long hi)
{
  return static_cast<int>(in.integer(i, e, lo, hi));
}

// compliance auto|material|<eps_n> <eps_t>
std::size_t read_compliance(const Reader &in, std::size_t i, const std::string &e, ParseState &st)
{
  Settings &s = st.s;
  if (!in.has(i + 1)) Reader::illegal(e);
  s.model.typed.compliance = true;
  if (in.at(i + 1) == "auto" || in.at(i + 1) == "material") {
    s.model.compliance.automatic = true;
    s.model.compliance.material = in.at(i + 1) == "material";
    return 2;
  }
  const double en = in.positive(i + 1, e);
  const double et = in.positive(i + 2, e);
  s.model.compliance.automatic = false;
  s.model.compliance.material = false;
  s.model.compliance.eps_n = en;
  s.model.compliance.eps_t = et;
  return 3;
}

std::size_t read_friction(const Reader &in, std::size_t i, const std::string &e, ParseState &st)
{
  const std::string &key = in.at(i);
  const double v = non_negative(in, i + 1, e);
  FrictionParams &f = st.s.model.friction;
  TypedCoefficients &typed = st.s.model.typed;
  (key == "mu" ? f.mu : key == "mu_roll" ? f.mu_roll : f.mu_twist) = v;
  (key == "mu" ? typed.mu : key == "mu_roll" ? typed.mu_roll : typed.mu_twist) = true;
  return 2;
}

std::size_t read_wall_keyword(const Reader &in, std::size_t i, const std::string &, ParseState &st)
{
  WallSpec w;
  const std::size_t used = read_wall(in, i, w);
  st.s.walls.push_back(w);
  return used;
}

// The keywords of the contacts a DEM deck sets.
std::vector<Keyword> contact_keywords()
{
  const KeywordTier U = KeywordTier::user;
  const std::string substeps = "auto|<integer 1 to " + std::to_string(kMaxSubsteps) + ">";
  return {
      {{"wall", U, "'wall [type <T> | <interaction>] <style> <args>'", "a wall (repeatable)"},
       read_wall_keyword},
      {{"compliance", U,
        "'compliance auto|material' or 'compliance <eps_n> <eps_t>' (positive numbers)",
        "the rows' compliance: the material's laws, rigid, or given"},
       read_compliance},
      {{"recovery_speed", U, quoted("recovery_speed", "auto|none|<positive speed>"),
        "the largest speed at which overlaps are removed"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         if (!in.has(i + 1)) Reader::illegal(e);
         const std::string &v = in.at(i + 1);
         st.s.model.recovery_speed = v == "auto" ? -1.0 : v == "none" ? 0.0 : in.positive(i + 1, e);
         return 2;
       }},
      {{"restitution", U, quoted("restitution", "<number in [0, 1]>"),
        "Newton's restitution of every contact"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         const double v = in.number(i + 1, e);
         if (!(v >= 0.0 && v <= 1.0)) Reader::illegal(e, &in.at(i + 1));
         st.s.model.restitution = v;
         st.s.model.typed.restitution = true;
         return 2;
       }},
      {{"substeps", U, quoted("substeps", substeps), "the contact solve's substeps a step"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         if (!in.has(i + 1)) Reader::illegal(e);
         st.s.model.substeps = in.at(i + 1) == "auto" ? 0 : count(in, i + 1, e, 1, kMaxSubsteps);
         return 2;
       }},
      {{"tol", U, quoted("tol", "none|<positive number>"), "the step's accuracy"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         const bool none = in.has(i + 1) && in.at(i + 1) == "none";
         st.s.step.accuracy = none ? 0.0 : in.positive(i + 1, e);
         return 2;
       }},
      {{"mu", U, quoted("mu", "<non-negative number>"), "Coulomb friction"}, read_friction},
      {{"mu_roll", U, quoted("mu_roll", "<non-negative number>"), "rolling resistance"},
       read_friction},
      {{"mu_twist", U, quoted("mu_twist", "<non-negative number>"), "twisting resistance"},
       read_friction},
      {{"coefficients", U, enum_form<CoefficientSource>("coefficients"),
        "friction and restitution from the pair style or this fix"},
       [](const Reader &in, std::size_t i, const std::string &, ParseState &st) -> std::size_t {
         st.s.model.coefficients = in.name<CoefficientSource>(i + 1, in.at(i));
         return 2;
       }},
      {{"rows", U, "'rows 3|6|auto'",
        "3: normal and tangential rows; 6: with rolling and twisting; auto: 6 where a law rolls "
        "or twists"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         long v = 0;
         if (!in.has(i + 1)) Reader::illegal(e);
         st.s.model.rows_auto = in.at(i + 1) == "auto";
         if (st.s.model.rows_auto) return 2;
         if (!to_long(in.at(i + 1), v) || (v != 3 && v != 6)) Reader::illegal(e, &in.at(i + 1));
         st.s.model.rows = static_cast<int>(v);
         return 2;
       }},
  };
}

// The keywords of a run: how often it solves, checks and exports, and with which solver.
std::vector<Keyword> run_keywords()
{
  const KeywordTier U = KeywordTier::user;
  return {
      {{"contact_every", U, quoted("contact_every", "auto|<integer 1 to 1000000>"),
        "the contacts solved every N steps, over N steps"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         if (!in.has(i + 1)) Reader::illegal(e);
         st.s.contact_every = in.at(i + 1) == "auto" ? 0 : count(in, i + 1, e, 1, 1000000);
         return 2;
       }},
      {{"clumps", U, "'clumps molecule|none'",
        "the spheres of one molecule move as one rigid body"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         if (!in.has(i + 1) || (in.at(i + 1) != "molecule" && in.at(i + 1) != "none"))
           Reader::illegal(e, in.has(i + 1) ? &in.at(i + 1) : nullptr);
         st.s.clumps = in.at(i + 1) == "molecule";
         return 2;
       }},
      {{"check", U, "'check <N>' (N a non-negative integer)",
        "every N steps, the step's error against the converged step"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.check_every = count(in, i + 1, e, 0, 2000000000L);
         return 2;
       }},
      {{"export", U, "'export <N> <file-prefix>' (N a positive integer)",
        "every N steps, the contact system to files"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.export_every = count(in, i + 1, e, 1, 2000000000L);
         if (!in.has(i + 2)) Reader::illegal(e);
         st.s.export_prefix = in.at(i + 2);
         return 3;
       }},
      {{"solver", U, enum_form<Method>("solver"), "the contact solver"},
       [](const Reader &in, std::size_t i, const std::string &, ParseState &st) -> std::size_t {
         st.s.step.solver = in.name<Method>(i + 1, in.at(i));
         return 2;
       }},
  };
}

// The keywords a DEM deck sets.
std::vector<Keyword> user_keywords()
{
  std::vector<Keyword> k = contact_keywords();
  for (Keyword &r : run_keywords()) k.push_back(std::move(r));
  return k;
}

constexpr const char *kLinearOnly =
    "outside the linear pass of solver cg, cr, minres or direct (this solver has none)";

// The tuning keywords of the linear pass (solver cg, cr, minres, direct).
std::vector<Keyword> linear_keywords()
{
  const KeywordTier T = KeywordTier::tuning;
  return {
      {{"form", T, enum_form<Form>("form"), "the linear pass's unknowns: bodies or impulses"},
       [](const Reader &in, std::size_t i, const std::string &, ParseState &st) -> std::size_t {
         st.s.step.form = in.name<Form>(i + 1, in.at(i));
         return 2;
       },
       sweeps_only,
       kLinearOnly},
      {{"precond", T, enum_form<PrecondKind>("precond"), "the Krylov solvers' preconditioner"},
       [](const Reader &in, std::size_t i, const std::string &, ParseState &st) -> std::size_t {
         st.s.step.precond.kind = in.name<PrecondKind>(i + 1, in.at(i));
         return 2;
       },
       sweeps_only,
       kLinearOnly},
      {{"weight", T, enum_form<EdgeWeight>("weight"), "the order in which fibres and trees grow"},
       [](const Reader &in, std::size_t i, const std::string &, ParseState &st) -> std::size_t {
         st.s.step.precond.weight = in.name<EdgeWeight>(i + 1, in.at(i));
         return 2;
       },
       [](const Settings &s) {
         const PrecondKind k = s.step.precond.kind;
         const bool grown = linear_pass(s) && (k == PrecondKind::fibre || k == PrecondKind::tree);
         return !grown && s.step.solver != Method::fbgs && !s.step.sweep_blocks;
       },
       "without fibres or trees (precond fibre or tree of a linear pass, solver fbgs)"},
      {{"linear_tol", T, quoted("linear_tol", "<positive number>"), "a linear solve's tolerance"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.stop.tol = in.positive(i + 1, e);
         return 2;
       },
       sweeps_only,
       kLinearOnly},
      {{"pass_tol", T, quoted("pass_tol", "<positive number>"),
        "the set-deciding passes' tolerance"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.pass_tol = in.positive(i + 1, e);
         return 2;
       },
       sweeps_only,
       kLinearOnly},
      {{"maxiter", T, quoted("maxiter", "<positive integer>"), "a linear solve's iterations"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.stop.max_iter = count(in, i + 1, e, 1, 100000000);
         return 2;
       },
       sweeps_only,
       kLinearOnly},
      {{"active_set", T, quoted("active_set", "<positive integer>"), "the active-set passes"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.active_set_max = count(in, i + 1, e, 1, 1000);
         return 2;
       },
       sweeps_only,
       kLinearOnly},
      {{"rescue_sweeps", T, quoted("rescue_sweeps", "<non-negative integer>"),
        "the sweeps of a step left far from sweep_tol"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.rescue_sweeps = count(in, i + 1, e, 0, 1000000);
         return 2;
       },
       [](const Settings &s) { return sweeps_only(s) || s.step.accuracy > 0; },
       "outside a linear pass with tol none"},
  };
}

// The tuning keywords of the sweeps.
std::vector<Keyword> sweep_keywords()
{
  const KeywordTier T = KeywordTier::tuning;
  return {
      {{"sweeps", T, quoted("sweeps", "<non-negative integer>"), "the most sweeps of a step"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.sweeps = count(in, i + 1, e, 0, 100000);
         st.sweeps_typed = true;
         return 2;
       }},
      {{"sweep_tol", T, quoted("sweep_tol", "<positive number>"),
        "the complementarity residual the sweeps aim at"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.sweep_tol = in.positive(i + 1, e);
         return 2;
       },
       // (after a linear pass it also decides whether the sweeps restart from the warm start)
       [](const Settings &s) { return s.step.accuracy > 0 && sweeps_only(s); },
       "with a tol and no linear pass (the sweeps stop on the tol's error estimate)"},
      {{"min_sweeps", T, quoted("min_sweeps", "<non-negative integer>"),
        "the sweeps before a tol may stop them"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.min_sweeps = count(in, i + 1, e, 0, 100000);
         return 2;
       },
       // it also sets where Anderson's mixing and focus_sweeps' period start
       [](const Settings &s) {
         const StepOptions &o = s.step;
         return !(o.accuracy > 0) && o.anderson == 0 && o.focus_sweeps == 0;
       },
       "with tol none, without anderson or focus_sweeps"},
      {{"focus_sweeps", T, quoted("focus_sweeps", "<non-negative integer>"),
        "the sweeps over only the contacts the last full one moved"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.focus_sweeps = count(in, i + 1, e, 0, 1000);
         return 2;
       }},
      {{"anderson", T, quoted("anderson", "<integer 0 to 50>"), "Anderson acceleration's depth"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.anderson = count(in, i + 1, e, 0, 50);
         st.anderson_typed = true;
         return 2;
       }},
      {{"anderson_period", T, quoted("anderson_period", "<integer 1 to 100>"),
        "the sweeps of Anderson's map"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.anderson_period = count(in, i + 1, e, 1, 100);
         return 2;
       },
       [](const Settings &s) { return s.step.anderson == 0; },
       "without Anderson acceleration"},
      {{"restart_sweeps", T, quoted("restart_sweeps", "<non-negative number>"),
        "a solve predicting more sweeps than this starts again (0: never)"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.step.restart_sweeps = non_negative(in, i + 1, e);
         return 2;
       },
       [](const Settings &s) { return s.step.anderson == 0 || !(s.step.accuracy > 0); },
       "without Anderson acceleration and a tol"},
      {{"sweep_groups", T, "'sweep_groups yes|no'", "four contacts at a time (AVX2)"},
       [](const Reader &in, std::size_t i, const std::string &, ParseState &st) -> std::size_t {
         st.s.step.sweep_groups = in.yes_no(i + 1, in.at(i));
         return 2;
       }},
      {{"sweep_cg", T, "'sweep_cg yes|no'", "deprecated: solver nncg"},
       [](const Reader &in, std::size_t i, const std::string &, ParseState &st) -> std::size_t {
         st.s.step.sweep_cg = in.yes_no(i + 1, in.at(i));
         return 2;
       },
       [](const Settings &) { return true; },
       "of its own: it is deprecated, and 'solver nncg' gives the same sweeps"},
      {{"sweep_blocks", T, "'sweep_blocks yes|no'", "deprecated: solver fbgs"},
       [](const Reader &in, std::size_t i, const std::string &, ParseState &st) -> std::size_t {
         st.s.step.sweep_blocks = in.yes_no(i + 1, in.at(i));
         return 2;
       },
       [](const Settings &) { return true; },
       "of its own: it is deprecated, and 'solver fbgs' gives the same sweeps"},
  };
}

// The tuning keywords of the contact model and the substeps.
std::vector<Keyword> model_keywords()
{
  const KeywordTier T = KeywordTier::tuning;
  return {
      {{"damping", T, quoted("damping", "<positive number of steps>"),
        "the constraints' relaxation time in steps"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.model.damping = in.positive(i + 1, e);
         return 2;
       }},
      {{"bounce_speed", T, quoted("bounce_speed", "auto|<non-negative speed>"),
        "the approach speed below which contacts stay plastic"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         if (!in.has(i + 1)) Reader::illegal(e);
         st.s.model.bounce_speed = in.at(i + 1) == "auto" ? -1.0 : non_negative(in, i + 1, e);
         return 2;
       }},
      {{"normal_relaxation", T, enum_form<NormalRelaxation>("normal_relaxation"),
        "a loaded material row's relaxation"},
       [](const Reader &in, std::size_t i, const std::string &, ParseState &st) -> std::size_t {
         st.s.model.normal_relaxation = in.name<NormalRelaxation>(i + 1, in.at(i));
         return 2;
       }},
      {{"substep_collisions", T,
        quoted("substep_collisions", "<positive number of collision times>"),
        "the longest substep of substeps auto"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         st.s.model.substep_collisions = in.positive(i + 1, e);
         return 2;
       }},
      {{"substep_when", T, "'substep_when always|moving'", "one solve where nothing moves"},
       [](const Reader &in, std::size_t i, const std::string &e, ParseState &st) -> std::size_t {
         if (!in.has(i + 1)) Reader::illegal(e);
         if (in.at(i + 1) != "always" && in.at(i + 1) != "moving")
           Reader::illegal(e, &in.at(i + 1));
         st.s.model.substep_moving_only = in.at(i + 1) == "moving";
         return 2;
       }},
  };
}

const std::vector<Keyword> &table()
{
  static const std::vector<Keyword> all = [] {
    std::vector<Keyword> t = user_keywords();
    for (auto part : {linear_keywords, sweep_keywords, model_keywords}) {
      std::vector<Keyword> more = part();
      t.insert(t.end(), more.begin(), more.end());
    }
    return t;
  }();
  return all;
}

const Keyword *find_keyword(const std::string &name)
{
  for (const Keyword &k : table())
    if (k.info.name == name) return &k;
  return nullptr;
}

std::string names_of(KeywordTier tier)
{
  std::string out;
  for (const Keyword &k : table())
    if (k.info.tier == tier) out += (out.empty() ? "" : ", ") + k.info.name;
  return out;
}

// The log's notes on typed tuning keywords that have no effect under the settings.
void note_inert(const std::vector<std::string> &typed, Settings &s)
{
  for (const Keyword &k : table()) {
    if (!k.inert || std::find(typed.begin(), typed.end(), k.info.name) == typed.end()) continue;
    if (k.inert(s)) s.notes.push_back("'" + k.info.name + "' has no effect " + k.inert_why);
  }
}

// The rules between keywords, after all are read.
void finish_settings(const ParseState &st, Settings &s)
{
  // a step accuracy needs room to reach it; a fast step (tol none) stops at its cap
  if (!st.sweeps_typed) s.step.sweeps = s.step.accuracy > 0 ? kAccuracySweeps : kFastSweeps;
  StepOptions &o = s.step;
  const bool plain =
      !(o.solver == Method::nncg || o.solver == Method::apgd || o.solver == Method::fbgs ||
        o.sweep_cg || o.sweep_blocks || o.focus_sweeps > 0);
  if (!plain && !st.anderson_typed) o.anderson = 0; // the default accelerates plain sweeps only
  if (!plain && o.anderson > 0)
    throw SettingsError("anderson accelerates plain sweeps: not with solver nncg, apgd or fbgs, "
                        "sweep_cg yes, sweep_blocks yes, or focus_sweeps");
  const FrictionParams &f = s.model.friction;
  if (!s.model.rows_auto && s.model.rows == 3 && (f.mu_roll > 0.0 || f.mu_twist > 0.0))
    throw SettingsError("mu_roll and mu_twist need 'rows 6' (rows 3 has no rotational rows)");
}

} // namespace

std::vector<KeywordInfo> keywords()
{
  std::vector<KeywordInfo> out;
  for (const Keyword &k : table()) out.push_back(k.info);
  return out;
}

Settings parse_settings(const std::vector<std::string> &args)
{
  Settings s;
  ParseState st{s};
  const Reader in(args);
  std::vector<std::string> typed;
  for (std::size_t i = 0; i < args.size();) {
    const Keyword *k = find_keyword(args[i]);
    if (!k)
      Reader::illegal("a keyword (" + names_of(KeywordTier::user) +
                          "; tuning: " + names_of(KeywordTier::tuning) + ")",
                      &args[i]);
    typed.push_back(args[i]);
    i += k->read(in, i, k->info.expected, st);
  }
  finish_settings(st, s);
  note_inert(typed, s);
  return s;
}

int steps_per_solve(double t_c, double dt)
{
  if (!(t_c > 0) || !(dt > 0)) return 1;
  const double steps = std::floor(kEveryCollisions * t_c / dt * (1.0 + 1e-12));
  return static_cast<int>(std::clamp(steps, 1.0, 1e6));
}

std::string describe(const Settings &s)
{
  const ComplianceParams &c = s.model.compliance;
  std::string out = describe(s.step) + ", rows " + std::to_string(s.model.rows) +
                    (s.model.rows_auto ? " (auto)" : "") + ", damping " +
                    format_g(s.model.damping) + ", compliance ";
  if (c.material)
    out += std::string("material (pair style, else ") + format_g(c.factor) + " dt^2 / m_min" +
           (s.model.typed.compliance ? ")" : "; the pair style is a material)");
  else if (c.automatic)
    out += "auto (" + format_g(c.factor) + " dt^2 / m_min)";
  else
    out += format_g(c.eps_n) + " " + format_g(c.eps_t);
  const double v = s.model.recovery_speed;
  out += ", recovery_speed " + (v < 0 ? "auto (" + format_g(s.model.recovery_radii) + " r_min / dt)"
                                : v == 0 ? std::string("none")
                                         : format_g(v));
  const double vb = s.model.bounce_speed;
  out += ", restitution " + format_g(s.model.restitution) + ", bounce_speed " +
         (vb < 0 ? "auto (" + format_g(s.model.bounce_steps) + " dt |f| / m max, or " +
                       format_g(s.model.recovery_radii) + " r_min / dt without forces)"
                 : format_g(vb));
  out += std::string(", coefficients ") + to_string(s.model.coefficients);
  out += std::string(", normal_relaxation ") + to_string(s.model.normal_relaxation);
  out += ", substeps " +
         (s.model.substeps > 0
              ? std::to_string(s.model.substeps)
              : "auto (at most " + format_g(s.model.substep_collisions) + " t_c each)");
  out += std::string(", substep_when ") + (s.model.substep_moving_only ? "moving" : "always");
  if (s.contact_every != 1)
    out += ", contact_every " +
           (s.contact_every > 0 ? std::to_string(s.contact_every)
                                : "auto (at most " + format_g(kEveryCollisions) + " t_c a solve)");
  if (s.clumps) out += ", clumps molecule";
  const FrictionParams &f = s.model.friction;
  return out + ", mu " + format_g(f.mu) + ", mu_roll " + format_g(f.mu_roll) + ", mu_twist " +
         format_g(f.mu_twist);
}

} // namespace fibre
