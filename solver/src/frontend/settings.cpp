#include "fibre/frontend/settings.hpp"

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

// The solver keywords; returns the words read, 0 when `key` is not one of them.
std::size_t read_solver_keyword(const Reader &in, std::size_t i, StepOptions &opt,
                                bool &sweeps_typed, bool &anderson_typed)
{
  const std::string &key = in.at(i);
  if (key == "form")
    opt.form = in.name<Form>(i + 1, key);
  else if (key == "solver")
    opt.solver = in.name<Method>(i + 1, key);
  else if (key == "precond")
    opt.precond.kind = in.name<PrecondKind>(i + 1, key);
  else if (key == "weight")
    opt.precond.weight = in.name<EdgeWeight>(i + 1, key);
  else if (key == "tol") {
    const std::string e = "'tol none|<positive number>'";
    opt.accuracy = in.has(i + 1) && in.at(i + 1) == "none" ? 0.0 : in.positive(i + 1, e);
  } else if (key == "linear_tol")
    opt.stop.tol = in.positive(i + 1, "'linear_tol <positive number>'");
  else if (key == "pass_tol")
    opt.pass_tol = in.positive(i + 1, "'pass_tol <positive number>'");
  else if (key == "maxiter")
    opt.stop.max_iter =
        static_cast<int>(in.integer(i + 1, "'maxiter <positive integer>'", 1, 100000000));
  else if (key == "active_set")
    opt.active_set_max =
        static_cast<int>(in.integer(i + 1, "'active_set <positive integer>'", 1, 1000));
  else if (key == "sweeps") {
    opt.sweeps = static_cast<int>(in.integer(i + 1, "'sweeps <non-negative integer>'", 0, 100000));
    sweeps_typed = true;
  } else if (key == "sweep_tol")
    opt.sweep_tol = in.positive(i + 1, "'sweep_tol <positive number>'");
  else if (key == "rescue_sweeps")
    opt.rescue_sweeps =
        static_cast<int>(in.integer(i + 1, "'rescue_sweeps <non-negative integer>'", 0, 1000000));
  else if (key == "min_sweeps")
    opt.min_sweeps =
        static_cast<int>(in.integer(i + 1, "'min_sweeps <non-negative integer>'", 0, 100000));
  else if (key == "focus_sweeps")
    opt.focus_sweeps =
        static_cast<int>(in.integer(i + 1, "'focus_sweeps <non-negative integer>'", 0, 1000));
  else if (key == "anderson") {
    opt.anderson = static_cast<int>(in.integer(i + 1, "'anderson <integer 0 to 50>'", 0, 50));
    anderson_typed = true;
  } else if (key == "anderson_period")
    opt.anderson_period =
        static_cast<int>(in.integer(i + 1, "'anderson_period <integer 1 to 100>'", 1, 100));
  else if (key == "sweep_cg")
    opt.sweep_cg = in.yes_no(i + 1, key);
  else if (key == "sweep_groups")
    opt.sweep_groups = in.yes_no(i + 1, key);
  else if (key == "sweep_blocks")
    opt.sweep_blocks = in.yes_no(i + 1, key);
  else
    return 0;
  return 2;
}

// The contact model's keywords (friction included); 0 when `key` is not one of them.
// compliance auto|material|<eps_n> <eps_t>
std::size_t read_compliance(const Reader &in, std::size_t i, Settings &s)
{
  const std::string e =
      "'compliance auto|material' or 'compliance <eps_n> <eps_t>' (positive numbers)";
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

// recovery_speed and bounce_speed: auto, a speed (recovery_speed also none)
std::size_t read_speed_keyword(const Reader &in, std::size_t i, Settings &s)
{
  const std::string &key = in.at(i);
  if (key == "recovery_speed") {
    const std::string e = "'recovery_speed auto|none|<positive speed>'";
    if (!in.has(i + 1)) Reader::illegal(e);
    const std::string &v = in.at(i + 1);
    if (v == "auto")
      s.model.recovery_speed = -1.0;
    else if (v == "none")
      s.model.recovery_speed = 0.0;
    else
      s.model.recovery_speed = in.positive(i + 1, e);
    return 2;
  }
  if (key == "bounce_speed") {
    const std::string e = "'bounce_speed auto|<non-negative speed>'";
    if (!in.has(i + 1)) Reader::illegal(e);
    if (in.at(i + 1) == "auto") {
      s.model.bounce_speed = -1.0;
      return 2;
    }
    const double v = in.number(i + 1, e);
    if (!(v >= 0.0)) Reader::illegal(e, &in.at(i + 1));
    s.model.bounce_speed = v;
    return 2;
  }
  return 0;
}

// substeps, substep_when, substep_collisions
std::size_t read_substep_keyword(const Reader &in, std::size_t i, Settings &s)
{
  const std::string &key = in.at(i);
  if (key == "substeps") {
    const std::string e = "'substeps auto|<integer 1 to " + std::to_string(kMaxSubsteps) + ">'";
    if (!in.has(i + 1)) Reader::illegal(e);
    s.model.substeps =
        in.at(i + 1) == "auto" ? 0 : static_cast<int>(in.integer(i + 1, e, 1, kMaxSubsteps));
    return 2;
  }
  if (key == "substep_when") {
    const std::string e = "'substep_when always|moving'";
    if (!in.has(i + 1)) Reader::illegal(e);
    if (in.at(i + 1) != "always" && in.at(i + 1) != "moving") Reader::illegal(e, &in.at(i + 1));
    s.model.substep_moving_only = in.at(i + 1) == "moving";
    return 2;
  }
  if (key == "substep_collisions") {
    s.model.substep_collisions =
        in.positive(i + 1, "'substep_collisions <positive number of collision times>'");
    return 2;
  }
  return 0;
}

std::size_t read_model_keyword(const Reader &in, std::size_t i, Settings &s)
{
  const std::string &key = in.at(i);
  if (key == "compliance") return read_compliance(in, i, s);
  if (key == "recovery_speed" || key == "bounce_speed") return read_speed_keyword(in, i, s);
  if (key == "substeps" || key == "substep_when" || key == "substep_collisions")
    return read_substep_keyword(in, i, s);
  if (key == "damping") {
    s.model.damping = in.positive(i + 1, "'damping <positive number of steps>'");
    return 2;
  }
  if (key == "mu" || key == "mu_roll" || key == "mu_twist") {
    const std::string e = "'" + key + " <non-negative number>'";
    const double v = in.number(i + 1, e);
    if (!(v >= 0.0)) Reader::illegal(e, &in.at(i + 1));
    FrictionParams &f = s.model.friction;
    TypedCoefficients &typed = s.model.typed;
    (key == "mu" ? f.mu : key == "mu_roll" ? f.mu_roll : f.mu_twist) = v;
    (key == "mu" ? typed.mu : key == "mu_roll" ? typed.mu_roll : typed.mu_twist) = true;
    return 2;
  }
  if (key == "restitution") {
    const std::string e = "'restitution <number in [0, 1]>'";
    const double v = in.number(i + 1, e);
    if (!(v >= 0.0 && v <= 1.0)) Reader::illegal(e, &in.at(i + 1));
    s.model.restitution = v;
    s.model.typed.restitution = true;
    return 2;
  }
  if (key == "coefficients") {
    s.model.coefficients = in.name<CoefficientSource>(i + 1, key);
    return 2;
  }
  if (key == "normal_relaxation") {
    s.model.normal_relaxation = in.name<NormalRelaxation>(i + 1, key);
    return 2;
  }
  if (key == "rows") {
    const std::string e = "'rows 3|6'";
    long v = 0;
    if (!in.has(i + 1)) Reader::illegal(e);
    if (!to_long(in.at(i + 1), v) || (v != 3 && v != 6)) Reader::illegal(e, &in.at(i + 1));
    s.model.rows = static_cast<int>(v);
    return 2;
  }
  return 0;
}

} // namespace

Settings parse_settings(const std::vector<std::string> &args)
{
  Settings s;
  const Reader in(args);
  std::size_t i = 0;
  bool sweeps_typed = false, anderson_typed = false;
  while (i < args.size()) {
    const std::string &key = args[i];
    std::size_t used = read_solver_keyword(in, i, s.step, sweeps_typed, anderson_typed);
    if (!used) used = read_model_keyword(in, i, s);
    if (!used && key == "wall") {
      WallSpec w;
      used = read_wall(in, i, w);
      s.walls.push_back(w);
    }
    if (!used && key == "export") {
      const std::string e = "'export <N> <file-prefix>' (N a positive integer)";
      s.export_every = static_cast<int>(in.integer(i + 1, e, 1, 2000000000L));
      if (!in.has(i + 2)) Reader::illegal(e);
      s.export_prefix = args[i + 2];
      used = 3;
    }
    if (!used && key == "check") {
      s.check_every = static_cast<int>(
          in.integer(i + 1, "'check <N>' (N a non-negative integer)", 0, 2000000000L));
      used = 2;
    }
    if (!used)
      Reader::illegal(
          "a keyword (form, solver, precond, weight, tol, linear_tol, pass_tol, maxiter, "
          "compliance, damping, mu, mu_roll, mu_twist, rows, active_set, sweeps, "
          "sweep_tol, rescue_sweeps, min_sweeps, focus_sweeps, anderson, anderson_period, "
          "sweep_cg, sweep_blocks, sweep_groups, recovery_speed, restitution, bounce_speed, "
          "coefficients, normal_relaxation, substeps, substep_collisions, substep_when, wall, "
          "export, check)",
          &key);
    i += used;
  }
  // a step accuracy needs room to reach it; a fast step (tol none) stops at its cap
  if (!sweeps_typed) s.step.sweeps = s.step.accuracy > 0 ? kAccuracySweeps : kFastSweeps;
  StepOptions &o = s.step;
  const bool plain =
      !(o.solver == Method::nncg || o.solver == Method::apgd || o.solver == Method::fbgs ||
        o.sweep_cg || o.sweep_blocks || o.focus_sweeps > 0);
  if (!plain && !anderson_typed) o.anderson = 0; // the default accelerates plain sweeps only
  if (!plain && o.anderson > 0)
    throw SettingsError("anderson accelerates plain sweeps: not with solver nncg, apgd or fbgs, "
                        "sweep_cg yes, sweep_blocks yes, or focus_sweeps");
  const FrictionParams &f = s.model.friction;
  if (s.model.rows == 3 && (f.mu_roll > 0.0 || f.mu_twist > 0.0))
    throw SettingsError("mu_roll and mu_twist need 'rows 6' (rows 3 has no rotational rows)");
  return s;
}

std::string describe(const Settings &s)
{
  const ComplianceParams &c = s.model.compliance;
  std::string out = describe(s.step) + ", rows " + std::to_string(s.model.rows) + ", damping " +
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
  const FrictionParams &f = s.model.friction;
  return out + ", mu " + format_g(f.mu) + ", mu_roll " + format_g(f.mu_roll) + ", mu_twist " +
         format_g(f.mu_twist);
}

} // namespace fibre
