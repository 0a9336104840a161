// The fix's keywords without LAMMPS: no keyword leaves every default of StepOptions{} and
// ContactModel{} (the one home of the defaults), each keyword sets what it names, and bad
// input names the keyword and its expected form.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "fibre/core/text.hpp"
#include "fibre/frontend/settings.hpp"

using namespace fibre;

namespace {

std::vector<std::string> words(const std::string &text)
{
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

std::string error_of(const std::string &text)
{
  try {
    parse_settings(words(text));
  } catch (SettingsError &e) {
    return e.what();
  }
  return "";
}

} // namespace

TEST(Settings, NoKeywordsKeepTheDefaults)
{
  const Settings s = parse_settings({});
  const StepOptions d{};
  EXPECT_EQ(describe(s.step), describe(d));
  // the measured defaults (doc/design.md section 4; bench/README.md section 7)
  EXPECT_EQ(d.form, Form::body);
  EXPECT_EQ(d.solver, Method::pgs);
  EXPECT_EQ(d.precond.kind, PrecondKind::tree);
  EXPECT_EQ(d.precond.weight, EdgeWeight::z);
  EXPECT_DOUBLE_EQ(d.stop.tol, 1e-4);
  EXPECT_EQ(d.stop.max_iter, 200);
  EXPECT_DOUBLE_EQ(d.pass_tol, 1e-3);
  EXPECT_EQ(d.active_set_max, 1);
  EXPECT_EQ(d.sweeps, kAccuracySweeps);
  EXPECT_DOUBLE_EQ(d.sweep_tol, 1e-3);
  EXPECT_DOUBLE_EQ(d.accuracy, 1e-4); // the step's accuracy
  EXPECT_EQ(d.anderson, 3);
  EXPECT_DOUBLE_EQ(s.model.friction.mu, 0.5);
  EXPECT_EQ(s.model.rows, 6);
  EXPECT_DOUBLE_EQ(s.model.damping, 2.0);
  EXPECT_TRUE(s.model.compliance.automatic);
  EXPECT_DOUBLE_EQ(s.model.compliance.factor, 1e-2);
  EXPECT_TRUE(s.walls.empty());
  EXPECT_EQ(s.export_every, 0);
  EXPECT_EQ(s.check_every, 0);
  EXPECT_EQ(
      describe(s),
      "form body, solver pgs, precond tree, weight z, tol 0.0001, linear_tol 0.0001, pass_tol "
      "0.001, maxiter 200, active_set 1, sweeps 2000, sweep_tol 0.001, rescue_sweeps 500, "
      "min_sweeps 10, focus_sweeps 0, anderson 3, anderson_period 2, restart_sweeps 200, rows 6 "
      "(auto), damping 2, "
      "compliance auto "
      "(0.01 dt^2 / m_min), recovery_speed auto (0.01 r_min / dt), restitution 0, "
      "bounce_speed auto (2 dt |f| / m max, or 0.01 r_min / dt without forces), coefficients "
      "pair, normal_relaxation spook, substeps auto (at most 0.33 t_c each), substep_when always, "
      "mu 0.5, "
      "mu_roll 0, mu_twist 0");
}

TEST(Settings, EveryKeywordSetsWhatItNames)
{
  const Settings s = parse_settings(
      words("form contact solver uzawa precond fibre weight impulse linear_tol 1e-6 "
            "pass_tol 1e-5 tol 2e-3 maxiter 77 compliance 1e-7 2e-7 damping 3 mu 0.3 mu_roll 0.1 "
            "mu_twist 0.05 rows 6 "
            "active_set 4 sweeps 9 sweep_tol 1e-4 wall zplane 0 NULL wall xplane -1 1 "
            "wall region box export 10 out/sys check 25"));
  EXPECT_EQ(s.step.form, Form::contact);
  EXPECT_EQ(s.step.solver, Method::cg); // uzawa is an alias
  EXPECT_EQ(s.step.precond.kind, PrecondKind::fibre);
  EXPECT_EQ(s.step.precond.weight, EdgeWeight::impulse);
  EXPECT_DOUBLE_EQ(s.step.stop.tol, 1e-6);
  EXPECT_DOUBLE_EQ(s.step.pass_tol, 1e-5);
  EXPECT_DOUBLE_EQ(s.step.accuracy, 2e-3);
  EXPECT_EQ(s.step.stop.max_iter, 77);
  EXPECT_FALSE(s.model.compliance.automatic);
  EXPECT_DOUBLE_EQ(s.model.compliance.eps_n, 1e-7);
  EXPECT_DOUBLE_EQ(s.model.compliance.eps_t, 2e-7);
  EXPECT_DOUBLE_EQ(s.model.damping, 3.0);
  EXPECT_DOUBLE_EQ(s.model.friction.mu, 0.3);
  EXPECT_DOUBLE_EQ(s.model.friction.mu_roll, 0.1);
  EXPECT_DOUBLE_EQ(s.model.friction.mu_twist, 0.05);
  EXPECT_EQ(s.step.active_set_max, 4);
  EXPECT_EQ(s.step.sweeps, 9);
  EXPECT_DOUBLE_EQ(s.step.sweep_tol, 1e-4);
  ASSERT_EQ(s.walls.size(), 3u);
  EXPECT_EQ(s.walls[0].kind, WallKind::zplane);
  EXPECT_TRUE(s.walls[0].has_lo);
  EXPECT_FALSE(s.walls[0].has_hi);
  EXPECT_EQ(s.walls[1].axis(), 0);
  EXPECT_DOUBLE_EQ(s.walls[1].lo, -1.0);
  EXPECT_DOUBLE_EQ(s.walls[1].hi, 1.0);
  EXPECT_EQ(s.walls[2].id, "box");
  const Settings typed = parse_settings(
      words("wall type 3 zplane 0 NULL wall granular hertz/material 1e5 1e3 0.3 tangential "
            "mindlin NULL 1.0 0.5 zplane 0 NULL wiggle z 0.1 2 wall hooke/history 4000.0 NULL "
            "100.0 NULL 0.5 1 region container mu 0.4"));
  ASSERT_EQ(typed.walls.size(), 3u);
  EXPECT_EQ(typed.walls[0].type, 3);
  EXPECT_TRUE(typed.walls[0].model.empty());
  EXPECT_EQ(typed.walls[1].type, 0);
  EXPECT_EQ(typed.walls[1].model,
            words("granular hertz/material 1e5 1e3 0.3 tangential mindlin NULL 1.0 0.5"));
  EXPECT_EQ(typed.walls[1].kind, WallKind::zplane);
  EXPECT_EQ(typed.walls[1].motion, WallMotion::wiggle);
  EXPECT_EQ(typed.walls[2].model, words("hooke/history 4000.0 NULL 100.0 NULL 0.5 1"));
  EXPECT_EQ(typed.walls[2].id, "container");
  EXPECT_DOUBLE_EQ(typed.model.friction.mu, 0.4);
  const Settings mesh = parse_settings(words("wall mesh hopper wall zplane 0 NULL"));
  ASSERT_EQ(mesh.walls.size(), 2u);
  EXPECT_EQ(mesh.walls[0].kind, WallKind::mesh);
  EXPECT_EQ(mesh.walls[0].id, "hopper");
  EXPECT_FALSE(mesh.walls[0].is_plane());
  EXPECT_TRUE(mesh.walls[1].is_plane());
  EXPECT_EQ(s.export_every, 10);
  EXPECT_EQ(s.export_prefix, "out/sys");
  EXPECT_EQ(s.check_every, 25);
  EXPECT_NE(describe(s).find("compliance 1e-07 2e-07"), std::string::npos);
  EXPECT_EQ(parse_settings(words("solver pgs")).step.solver, Method::pgs);
  EXPECT_EQ(parse_settings(words("solver fbgs")).step.solver, Method::fbgs);
  const Settings blocks = parse_settings(words("sweep_blocks yes"));
  EXPECT_TRUE(blocks.step.sweep_blocks);
  EXPECT_NE(describe(blocks.step).find("sweep_blocks yes"), std::string::npos);
  EXPECT_FALSE(parse_settings(words("sweep_blocks no")).step.sweep_blocks);
  EXPECT_TRUE(parse_settings({}).step.sweep_groups);
  const Settings one_by_one = parse_settings(words("sweep_groups no"));
  EXPECT_FALSE(one_by_one.step.sweep_groups);
  EXPECT_NE(describe(one_by_one.step).find("sweep_groups no"), std::string::npos);
  EXPECT_EQ(describe(parse_settings(words("sweep_groups yes")).step), describe(StepOptions{}));
  EXPECT_EQ(parse_settings(words("rescue_sweeps 0")).step.rescue_sweeps, 0);
  EXPECT_EQ(parse_settings(words("rescue_sweeps 2000")).step.rescue_sweeps, 2000);
  EXPECT_EQ(parse_settings(words("min_sweeps 0")).step.min_sweeps, 0);
  EXPECT_EQ(parse_settings(words("min_sweeps 25")).step.min_sweeps, 25);
  EXPECT_DOUBLE_EQ(parse_settings(words("recovery_speed 0.3")).model.recovery_speed, 0.3);
  EXPECT_DOUBLE_EQ(parse_settings(words("recovery_speed none")).model.recovery_speed, 0.0);
  const ContactModel automatic = parse_settings(words("recovery_speed auto")).model;
  EXPECT_DOUBLE_EQ(automatic.max_recovery(0.01, 0.5), 0.01 * 0.5 / 0.01);
  EXPECT_DOUBLE_EQ(parse_settings(words("recovery_speed 0.3")).model.max_recovery(0.01, 0.5), 0.3);
  EXPECT_EQ(parse_settings(words("solver mumps")).step.solver, Method::direct);
  EXPECT_EQ(parse_settings(words("anderson 0")).step.anderson, 0);
  EXPECT_EQ(parse_settings(words("anderson 5")).step.anderson, 5);
  // the default accelerates plain sweeps only
  EXPECT_EQ(parse_settings(words("solver nncg")).step.anderson, 0);
  EXPECT_EQ(parse_settings(words("focus_sweeps 3")).step.anderson, 0);
  EXPECT_EQ(parse_settings(words("solver cg")).step.anderson, 3);
  EXPECT_NE(describe(parse_settings(words("anderson 3")).step).find("anderson 3"),
            std::string::npos);
  EXPECT_EQ(parse_settings(words("anderson_period 1")).step.anderson_period, 1);
  EXPECT_EQ(parse_settings(words("anderson_period 3")).step.anderson_period, 3);
  EXPECT_NE(describe(parse_settings(words("anderson_period 1")).step).find("anderson_period 1"),
            std::string::npos);
  // without Anderson its period means nothing
  EXPECT_EQ(describe(parse_settings(words("anderson 0")).step).find("anderson_period"),
            std::string::npos);
}

// Strict numbers: the whole word, finite; an underflow to a subnormal is a number, an overflow
// is not.
TEST(Settings, StrictNumbers)
{
  double x = 0;
  EXPECT_TRUE(to_double("-9.8813129168249309e-324", x));
  EXPECT_EQ(x, -9.8813129168249309e-324);
  EXPECT_TRUE(to_double("1e-400", x)); // underflows to 0
  EXPECT_FALSE(to_double("1e400", x));
  EXPECT_FALSE(to_double("inf", x));
  EXPECT_FALSE(to_double("1.5x", x));
  EXPECT_FALSE(to_double("", x));
  long n = 0;
  EXPECT_TRUE(to_long("-12", n));
  EXPECT_EQ(n, -12);
  EXPECT_FALSE(to_long("12.0", n));
  EXPECT_FALSE(to_long("99999999999999999999999", n));
}

// A step accuracy needs room to reach it: the sweeps' cap rises unless typed.
TEST(Settings, TolIsTheStepAccuracyAndRaisesTheSweepCap)
{
  EXPECT_EQ(parse_settings(words("tol 1e-3")).step.sweeps, kAccuracySweeps);
  EXPECT_DOUBLE_EQ(parse_settings(words("tol 1e-3")).step.accuracy, 1e-3);
  EXPECT_EQ(parse_settings(words("sweeps 300 tol 1e-3")).step.sweeps, 300);
  EXPECT_EQ(parse_settings(words("tol 1e-3 sweeps 300")).step.sweeps, 300);
  EXPECT_EQ(parse_settings(words("tol none")).step.sweeps, kFastSweeps);
  EXPECT_EQ(parse_settings(words("tol none sweeps 80")).step.sweeps, 80);
  EXPECT_DOUBLE_EQ(parse_settings(words("tol 1e-3 tol none")).step.accuracy, 0.0);
}

TEST(Settings, BadInputNamesTheKeywordAndItsForm)
{
  EXPECT_EQ(error_of("form primal"), "expected 'form body|contact', got 'primal'");
  EXPECT_EQ(error_of("solver bicgstab"),
            "expected 'solver cg|cr|minres|direct|pgs|nncg|fbgs|apgd', got 'bicgstab'");
  EXPECT_EQ(error_of("precond"), "expected 'precond none|jacobi|block|fibre|tree'");
  EXPECT_EQ(error_of("tol -1"), "expected 'tol none|<positive number>', got '-1'");
  EXPECT_EQ(error_of("tol 1e-3x"), "expected 'tol none|<positive number>', got '1e-3x'");
  EXPECT_EQ(error_of("tol"), "expected 'tol none|<positive number>'");
  EXPECT_EQ(error_of("linear_tol nan"), "expected 'linear_tol <positive number>', got 'nan'");
  EXPECT_EQ(error_of("maxiter 2.5"), "expected 'maxiter <positive integer>', got '2.5'");
  EXPECT_EQ(error_of("sweeps -1"), "expected 'sweeps <non-negative integer>', got '-1'");
  EXPECT_EQ(error_of("mu -0.1"), "expected 'mu <non-negative number>', got '-0.1'");
  EXPECT_EQ(error_of("rows 4"), "expected 'rows 3|6|auto', got '4'");
  EXPECT_EQ(error_of("clumps rigid"), "expected 'clumps molecule|none', got 'rigid'");
  EXPECT_EQ(error_of("clumps"), "expected 'clumps molecule|none'");
  EXPECT_TRUE(parse_settings(words("clumps molecule")).clumps);
  EXPECT_FALSE(parse_settings(words("clumps molecule clumps none")).clumps);
  EXPECT_EQ(error_of("recovery_speed -1"),
            "expected 'recovery_speed auto|none|<positive speed>', got '-1'");
  EXPECT_EQ(error_of("restitution 1.5"), "expected 'restitution <number in [0, 1]>', got '1.5'");
  EXPECT_EQ(error_of("restitution"), "expected 'restitution <number in [0, 1]>'");
  EXPECT_EQ(error_of("bounce_speed -2"),
            "expected 'bounce_speed auto|<non-negative speed>', got '-2'");
  EXPECT_EQ(parse_settings(words("restitution 0.5 bounce_speed 0.2")).model.restitution, 0.5);
  EXPECT_EQ(parse_settings(words("restitution 0.5 bounce_speed 0.2")).model.bounce_speed, 0.2);
  EXPECT_EQ(error_of("compliance 1e-6"),
            "expected 'compliance auto|material' or 'compliance <eps_n> <eps_t>' (positive "
            "numbers)");
  EXPECT_EQ(error_of("wall zplane NULL NULL"),
            "expected 'wall zplane <lo|NULL> <hi|NULL>' with at least one of lo and hi a number");
  EXPECT_EQ(error_of("wall zplane 2 1"),
            "expected 'wall zplane <lo|NULL> <hi|NULL>' with lo < hi, got '2 1'");
  EXPECT_EQ(error_of("wall region"), "expected 'wall region <region-ID>'");
  EXPECT_EQ(error_of("wall mesh"), "expected 'wall mesh <fix-ID>' (a fix mesh/surface)");
  EXPECT_EQ(error_of("wall cylinder 3"),
            "expected 'wall xplane|yplane|zplane <lo|NULL> <hi|NULL>', 'wall "
            "xcylinder|ycylinder|zcylinder <radius> [<c1> <c2>]', 'wall region <region-ID>' or "
            "'wall mesh <fix-ID>' (optionally 'type <T>' or fix wall/gran's interaction after "
            "'wall'), got 'cylinder'");
  // a wall's own material: an atom type, or the interaction words of the fix wall/gran it
  // replaces, up to the wall's style
  EXPECT_EQ(error_of("wall type 0 zplane 0 NULL"),
            "expected 'wall type <T> <style> ...' (T an atom type), got '0'");
  EXPECT_EQ(error_of("wall granular hertz/material 1e5 0.3 0.3"),
            "expected 'wall granular <coefficients> xplane|yplane|zplane|zcylinder|region ...' "
            "(fix wall/gran's interaction and arguments, then the wall's style)");
  EXPECT_EQ(error_of("wall type 1 zcylinder 0"),
            "expected 'wall zcylinder <radius> [<c1> <c2>]' (radius > 0), got '0'");
  EXPECT_EQ(error_of("wall zcylinder 2 0 0 wiggle z 1 1"),
            "expected 'wall zcylinder <radius> [<c1> <c2>]' (radius > 0) without motion (a "
            "cylinder wall stands still), got 'wiggle'");
  EXPECT_EQ(error_of("wall type 2 cylinder 3"),
            "expected 'wall xplane|yplane|zplane <lo|NULL> <hi|NULL>', 'wall "
            "xcylinder|ycylinder|zcylinder <radius> [<c1> <c2>]', 'wall region <region-ID>' or "
            "'wall mesh <fix-ID>' (optionally 'type <T>' or fix wall/gran's interaction after "
            "'wall'), got 'cylinder'");
  EXPECT_EQ(error_of("export 10"), "expected 'export <N> <file-prefix>' (N a positive integer)");
  EXPECT_EQ(error_of("check -1"), "expected 'check <N>' (N a non-negative integer), got '-1'");
  EXPECT_EQ(error_of("check"), "expected 'check <N>' (N a non-negative integer)");
  EXPECT_EQ(error_of("anderson 51"), "expected 'anderson <integer 0 to 50>', got '51'");
  EXPECT_EQ(error_of("anderson_period 0"),
            "expected 'anderson_period <integer 1 to 100>', got '0'");
  EXPECT_EQ(error_of("anderson_period"), "expected 'anderson_period <integer 1 to 100>'");
  EXPECT_EQ(error_of("solver nncg anderson 3"),
            "anderson accelerates plain sweeps: not with solver nncg, apgd or fbgs, sweep_cg yes, "
            "sweep_blocks yes, or focus_sweeps");
  EXPECT_TRUE(parse_settings(words("rows 3 rows auto mu_roll 0.1")).model.rows_auto);
  EXPECT_FALSE(parse_settings(words("rows 6")).model.rows_auto);
  EXPECT_EQ(error_of("rows 3 mu_roll 0.1"),
            "mu_roll and mu_twist need 'rows 6' (rows 3 has no rotational rows)");
  EXPECT_EQ(error_of("substeps 0"), "expected 'substeps auto|<integer 1 to 1000>', got '0'");
  EXPECT_EQ(error_of("substeps two"), "expected 'substeps auto|<integer 1 to 1000>', got 'two'");
  EXPECT_EQ(error_of("substeps"), "expected 'substeps auto|<integer 1 to 1000>'");
  EXPECT_EQ(error_of("substep_collisions 0"),
            "expected 'substep_collisions <positive number of collision times>', got '0'");
  EXPECT_EQ(error_of("contact_every 0"),
            "expected 'contact_every auto|<integer 1 to 1000000>', got '0'");
  EXPECT_EQ(error_of("contact_every"), "expected 'contact_every auto|<integer 1 to 1000000>'");
  EXPECT_EQ(parse_settings(words("contact_every 4")).contact_every, 4);
  EXPECT_EQ(parse_settings(words("contact_every 4 contact_every auto")).contact_every, 0);
  EXPECT_EQ(parse_settings(words("")).contact_every, 1);
  EXPECT_EQ(parse_settings(words("substeps 7")).model.substeps, 7);
  EXPECT_EQ(parse_settings(words("substeps 7 substeps auto")).model.substeps, 0);
  EXPECT_DOUBLE_EQ(parse_settings(words("substep_collisions 0.3")).model.substep_collisions, 0.3);
  EXPECT_EQ(error_of("substep_when rest"), "expected 'substep_when always|moving', got 'rest'");
  EXPECT_EQ(error_of("substep_when"), "expected 'substep_when always|moving'");
  EXPECT_TRUE(parse_settings(words("substep_when moving")).model.substep_moving_only);
  EXPECT_FALSE(
      parse_settings(words("substep_when moving substep_when always")).model.substep_moving_only);
  EXPECT_NE(error_of("speed 3").find("expected a keyword (wall, compliance"), std::string::npos);
  EXPECT_NE(error_of("speed 3").find("; tuning: form, precond"), std::string::npos);
  EXPECT_NE(error_of("speed 3").find("got 'speed'"), std::string::npos);
}

// Moving planes: fix wall/gran's wiggle and shear after a plane's bounds, their offset and
// velocity in time, and their errors.
TEST(Settings, MovingPlanes)
{
  const Settings s = parse_settings(
      words("wall zplane 0 NULL wiggle z 0.1 0.5 wall xplane -2 2 shear y 1.5 mu 0.3"));
  ASSERT_EQ(s.walls.size(), 2u);
  const WallSpec &w = s.walls[0];
  EXPECT_EQ(w.motion, WallMotion::wiggle);
  EXPECT_NEAR(w.offset(0.125), 0.1, 1e-15); // a quarter period
  EXPECT_NEAR(w.velocity(0.0)[2], 0.1 * 2 * M_PI / 0.5, 1e-12);
  const WallSpec &x = s.walls[1];
  EXPECT_EQ(x.motion, WallMotion::shear);
  EXPECT_EQ(x.offset(3.0), 0.0);
  EXPECT_EQ(x.velocity(3.0), Vec3(0, 1.5, 0));
  EXPECT_DOUBLE_EQ(s.model.friction.mu, 0.3); // parsing goes on after the motion
  // an in-plane wiggle slides the plane without moving it
  const Settings t = parse_settings(words("wall zplane 0 NULL wiggle x 0.1 0.5"));
  EXPECT_EQ(t.walls[0].offset(0.125), 0.0);
  EXPECT_NEAR(t.walls[0].velocity(0.0)[0], 0.1 * 2 * M_PI / 0.5, 1e-12);
  // a plane sheared along its own normal, a bad axis, a zero period
  EXPECT_EQ(error_of("wall zplane 0 NULL shear z 1"),
            "expected 'shear x|y|z <speed>' (x, y or z in the wall's plane), got 'z'");
  EXPECT_EQ(error_of("wall zplane 0 NULL wiggle w 1 1"),
            "expected 'wiggle x|y|z <amplitude> <period>' (period > 0), got 'w'");
  EXPECT_EQ(error_of("wall zplane 0 NULL wiggle z 1 0"),
            "expected 'wiggle x|y|z <amplitude> <period>' (period > 0), got '0'");
}

// The keyword table: every name once, the user tier first, and its error forms as the readers
// give them.
TEST(Settings, OneTableOfKeywordsInTwoTiers)
{
  const std::vector<KeywordInfo> all = keywords();
  std::set<std::string> names;
  bool tuning_seen = false;
  for (const KeywordInfo &k : all) {
    EXPECT_TRUE(names.insert(k.name).second) << k.name;
    if (k.tier == KeywordTier::tuning) tuning_seen = true;
    EXPECT_FALSE(tuning_seen && k.tier == KeywordTier::user) << k.name << " after a tuning one";
    EXPECT_FALSE(k.help.empty()) << k.name;
  }
  EXPECT_EQ(all.size(), 39u);
  for (const char *bad : {"tol -1", "linear_tol 0", "anderson 99", "substep_when rest"}) {
    const std::vector<std::string> w = words(bad);
    const auto k =
        std::find_if(all.begin(), all.end(), [&](const KeywordInfo &i) { return i.name == w[0]; });
    ASSERT_NE(k, all.end());
    EXPECT_EQ(error_of(bad), "expected " + k->expected + ", got '" + w[1] + "'");
  }
}

// The doc page's Syntax lists the table's keywords in the same two tiers.
TEST(Settings, TheDocPageListsTheTable)
{
  std::ifstream in(std::string(FIBRE_TEST_DATA_DIR) + "/../../doc/fix_fibre_contact.md");
  ASSERT_TRUE(in.good());
  // "* user keyword (...) = *a*, *b* ..." and its indented continuation lines
  std::map<std::string, std::set<std::string>> listed; // tier -> names
  std::string line, tier;
  while (std::getline(in, line)) {
    const bool continued = line.rfind("  ", 0) == 0;
    if (!continued) tier.clear();
    if (line.rfind("* user keyword", 0) == 0) tier = "user";
    if (line.rfind("* tuning keyword", 0) == 0) tier = "tuning";
    if (tier.empty()) continue;
    const std::size_t from = continued ? 0 : line.find('=');
    for (std::size_t a = line.find('*', from + 1); a != std::string::npos;) {
      const std::size_t b = line.find('*', a + 1);
      if (b == std::string::npos) break;
      listed[tier].insert(line.substr(a + 1, b - a - 1));
      a = line.find('*', b + 1);
    }
  }
  std::map<std::string, std::set<std::string>> table;
  for (const KeywordInfo &k : keywords())
    table[k.tier == KeywordTier::user ? "user" : "tuning"].insert(k.name);
  EXPECT_EQ(listed["user"], table["user"]);
  EXPECT_EQ(listed["tuning"], table["tuning"]);
}

// A typed tuning keyword that has no effect under the chosen solver is noted for the log.
TEST(Settings, InertTuningKeywordsAreNoted)
{
  const auto notes = [](const char *text) { return parse_settings(words(text)).notes; };
  const auto noted = [&](const char *text, const std::string &what) {
    for (const std::string &n : notes(text))
      if (n.find(what) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(noted("precond tree", "'precond' has no effect"));
  EXPECT_TRUE(noted("linear_tol 1e-6 maxiter 50", "'maxiter' has no effect"));
  EXPECT_TRUE(notes("solver cg precond tree linear_tol 1e-6").empty());
  EXPECT_TRUE(noted("sweep_tol 1e-3", "'sweep_tol' has no effect with a tol"));
  EXPECT_TRUE(notes("tol none sweep_tol 1e-3").empty());
  EXPECT_TRUE(notes("solver cg sweep_tol 1e-3").empty()); // the restart after a linear pass
  EXPECT_TRUE(noted("tol none anderson 0 min_sweeps 4", "'min_sweeps' has no effect"));
  EXPECT_TRUE(notes("tol none min_sweeps 4").empty()); // Anderson mixes from min_sweeps on
  EXPECT_TRUE(noted("anderson 0 anderson_period 3", "'anderson_period' has no effect"));
  EXPECT_TRUE(noted("sweep_cg yes", "deprecated"));
  EXPECT_TRUE(noted("weight impulse", "'weight' has no effect"));
  EXPECT_TRUE(notes("solver fbgs weight impulse").empty());
  EXPECT_TRUE(notes("").empty());
  EXPECT_TRUE(notes("wall zplane 0 NULL mu 0.3 tol 1e-5 substeps 2").empty());
}
