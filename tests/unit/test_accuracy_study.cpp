// The accuracy study on a shipped exported step (examples/material, N 350, step 600: 348
// contacts, exported with its warm start by fix fibre_contact under the defaults of then,
// solver cg tol none): the export is the whole step (replaying that solve from its warm start
// gives the run's impulses again), the two
// reference methods agree, and the measure orders the solvers as they are: more sweeps are
// more accurate, nonlinear CG beats plain sweeps at equal count.
#include <gtest/gtest.h>

#include "fibre/frontend/settings.hpp"
#include "fibre/io/system_io.hpp"
#include "fibre/solvers/pgs.hpp"
#include "fibre/study/accuracy_study.hpp"
#include "reference.hpp"

#include <cstdio>
#include <fstream>
#include <unistd.h>

using namespace fibre;

namespace {

const std::string kState = std::string(FIBRE_TEST_DATA_DIR) + "/material350_step600";

StepOptions sweeps_only(Method m, int sweeps)
{
  StepOptions o;
  o.solver = m;
  o.sweeps = sweeps;
  o.sweep_tol = 1e-14;
  o.accuracy = 0; // exactly `sweeps` sweeps
  o.anderson = 0; // plain sweeps (Anderson acceleration has its own test)
  return o;
}

// The former defaults, with which the shipped state was exported: the tree-CG pass
// and at most 50 sweeps, no step accuracy, every sweep full, one contact at a time.
StepOptions former_default()
{
  return parse_settings({"solver", "cg", "tol", "none", "focus_sweeps", "0", "anderson", "0",
                         "sweep_groups", "no"})
      .step;
}

} // namespace

TEST(AccuracyStudy, ExportedStepReplaysAndHasAConfirmedReference)
{
  const StepState st = read_step_state(kState);
  ASSERT_EQ(st.sys.num_contacts(), 348);
  EXPECT_GT(st.warm.norm(), 0.0);
  const Reference ref = nonsmooth_reference(st.sys, st.lambda);
  EXPECT_LE(ref.complementarity_pgs, 1e-10);
  EXPECT_TRUE(ref.newton.converged);
  EXPECT_TRUE(ref.confirmed()) << ref.agreement.velocity() << " " << ref.agreement.impulse();

  // the run's solve, replayed from the exported warm start, is the run's own solve
  const double tk = k_product_seconds(st.sys, 5);
  const StudyRow def = measure_setting(st, former_default(), ref.lambda, tk, 1);
  const StepAccuracy run = step_accuracy(st.sys, st.lambda, ref.lambda);
  EXPECT_NEAR(def.error.velocity(), run.velocity(), 1e-12 * run.velocity());
  // measured 5.1e-3 / 2.6e-2 (translational / rotational): the former default misses issue
  // #13's 1e-3, which these figures track
  EXPECT_GT(def.error.velocity(), 1e-3);
  EXPECT_LT(def.error.velocity(), 0.1);

  const StudyRow pgs50 = measure_setting(st, sweeps_only(Method::pgs, 50), ref.lambda, tk, 1);
  const StudyRow nncg50 = measure_setting(st, sweeps_only(Method::nncg, 50), ref.lambda, tk, 1);
  const StudyRow pgs2000 = measure_setting(st, sweeps_only(Method::pgs, 2000), ref.lambda, tk, 1);
  EXPECT_EQ(pgs50.sweeps, 50);
  EXPECT_LT(nncg50.error.velocity(), pgs50.error.velocity());
  EXPECT_LT(pgs2000.error.velocity(), 1e-6);
  EXPECT_LT(pgs2000.error.impulse(), 1e-6);
}

// The sweeps' error estimate (f_ID[16]) against the true error of the normal impulses, for the
// default, for projected Gauss-Seidel cut at several counts, and for the fibre-block sweeps and
// APGD (whose estimate comes from its residual's contraction): within a factor of 3.
TEST(AccuracyStudy, ErrorEstimateTracksTheTrueError)
{
  const StepState st = read_step_state(kState);
  const Reference ref = nonsmooth_reference(st.sys, st.lambda);
  std::vector<StepOptions> settings = {StepOptions{}};
  for (int sweeps : {20, 50, 200, 500}) settings.push_back(sweeps_only(Method::pgs, sweeps));
  for (int sweeps : {50, 200}) {
    settings.push_back(sweeps_only(Method::fbgs, sweeps));
    settings.push_back(sweeps_only(Method::apgd, sweeps));
  }
  for (const StepOptions &o : settings) {
    const StudyRow row = measure_setting(st, o, ref.lambda, 1.0, 1);
    SCOPED_TRACE(describe(o));
    ASSERT_GT(row.sweeps, 5);
    EXPECT_LT(row.error_estimate, 3.0 * row.error.lambda_n);
    EXPECT_GT(row.error_estimate, row.error.lambda_n / 3.0);
  }
}

// tol is the step's accuracy: the sweeps go on until their error estimate is within it. For the
// default solver and the Gauss-Seidel ones the step's true errors against the reference follow
// tol down: the normal impulses within 1.5 tol (measured 0.8 to 1.05 tol), the velocity change
// within 3 tol (its rotational part, 2.1 tol), every impulse group within 10 tol (rolling,
// 5.8 to 7 tol); each costs more sweeps than a looser tol. (The estimate of nncg and apgd runs
// 5 to 8x optimistic at 1e-3, the doc page says so.)
TEST(AccuracyStudy, TolIsTheStepsAccuracy)
{
  const StepState st = read_step_state(kState);
  const Reference ref = nonsmooth_reference(st.sys, st.lambda);
  const std::vector<std::vector<std::string>> families = {
      {"solver", "cg"}, {"solver", "pgs"}, {"solver", "fbgs"}, {"solver", "pgs", "anderson", "0"}};
  for (const auto &family : families) {
    int last_sweeps = 0;
    for (double tol : {1e-2, 1e-3, 1e-4}) {
      std::vector<std::string> words = family;
      words.insert(words.end(), {"tol", std::to_string(tol)});
      const StepOptions o = parse_settings(words).step;
      const StudyRow row = measure_setting(st, o, ref.lambda, 1.0, 1);
      SCOPED_TRACE(describe(o));
      EXPECT_TRUE(row.converged);
      EXPECT_LE(row.error_estimate, tol);
      EXPECT_LT(row.error.lambda_n, 1.5 * tol);
      EXPECT_LT(row.error.velocity(), 3 * tol);
      EXPECT_LT(row.error.impulse(), 10 * tol);
      EXPECT_GT(row.sweeps, last_sweeps);
      last_sweeps = row.sweeps;
    }
  }
  // Issue #13's acceptance: the default (projected Gauss-Seidel to tol 1e-4) meets velocity
  // 1e-3 and impulses 1e-2 on this state against the reference computed here (measured 6.1e-5
  // and 5.8e-4), where the former default (solver cg tol none) misses them; and the parser's
  // defaults are StepOptions{}.
  const StudyRow def = measure_setting(st, StepOptions{}, ref.lambda, 1.0, 1);
  const StudyRow former = measure_setting(st, former_default(), ref.lambda, 1.0, 1);
  EXPECT_LT(def.error.velocity(), 1e-3);
  EXPECT_LT(def.error.impulse(), 1e-2);
  // and its own tol as every tol above: velocity within 3 tol, every impulse group 10 tol
  EXPECT_LT(def.error.velocity(), 3e-4);
  EXPECT_LT(def.error.impulse(), 1e-3);
  EXPECT_TRUE(def.converged);
  EXPECT_GT(former.error.velocity(), 1e-3);
  EXPECT_EQ(describe(parse_settings({}).step), describe(StepOptions{}));
}

// Anderson acceleration (anderson M) meets the same tol on a fraction of the sweeps: on this
// state plain sweeps contract by about 0.98 a sweep, and the combination removes the slow
// modes together. Its estimate (2 |f| / sigma, PgsResult::singular_value) keeps the errors
// within the plain sweeps' (checked above for every tol), whether its map is one sweep or
// several (anderson_period; the default mixes after every second).
TEST(AccuracyStudy, AndersonMeetsTheToleranceOnFewerSweeps)
{
  const StepState st = read_step_state(kState);
  const Reference ref = nonsmooth_reference(st.sys, st.lambda);
  for (double tol : {1e-3, 1e-4, 1e-6}) {
    const std::string t = std::to_string(tol);
    const StudyRow plain =
        measure_setting(st, parse_settings({"tol", t, "anderson", "0"}).step, ref.lambda, 1.0, 1);
    for (const char *period : {"1", "2", "3"}) {
      const StudyRow fast = measure_setting(
          st, parse_settings({"tol", t, "anderson", "3", "anderson_period", period}).step,
          ref.lambda, 1.0, 1);
      std::printf("tol %g: anderson 0: %d sweeps, lambda_n %.3g, velocity %.3g; anderson 3, "
                  "period %s: %d sweeps, %.3g, %.3g\n",
                  tol, plain.sweeps, plain.error.lambda_n, plain.error.velocity(), period,
                  fast.sweeps, fast.error.lambda_n, fast.error.velocity());
      EXPECT_TRUE(fast.converged);
      EXPECT_LT(fast.sweeps, 0.4 * plain.sweeps); // measured 0.16 to 0.24 at 1e-4
      EXPECT_LT(fast.error.lambda_n, 1.5 * tol);
      EXPECT_LT(fast.error.velocity(), 3 * tol);
    }
  }
}

TEST(AccuracyStudy, BadStateFilesAreNamed)
{
  EXPECT_THROW(read_step_state("/nonexistent/state"), std::runtime_error);
  const std::string path = "/tmp/fibre_bad_state_" + std::to_string(::getpid());
  {
    const StepState st = read_step_state(kState);
    std::ofstream sys(path + ".sys");
    write_system(sys, st.sys);
    std::ofstream lam(path + ".lambda");
    lam << "# header\n0 1 2 0 1 2 3\n"; // too few values
  }
  try {
    read_step_state(path);
    ADD_FAILURE() << "accepted a bad .lambda";
  } catch (const std::runtime_error &e) {
    EXPECT_NE(std::string(e.what()).find(".lambda, line 2"), std::string::npos) << e.what();
  }
  // an images file must pair a ghost with an owned body (this system has no ghosts)
  {
    const StepState st = read_step_state(kState);
    std::ofstream lam(path + ".lambda");
    lam << "# header\n";
    for (int c = 0; c < st.sys.num_contacts(); ++c) {
      lam << c << " 0 0 0";
      for (int r = 0; r < st.sys.rows(); ++r) lam << " 0";
      lam << "\n";
    }
    std::ofstream images(path + ".images");
    images << "# image body\n0 1\n";
  }
  try {
    read_step_state(path);
    ADD_FAILURE() << "accepted a bad .images";
  } catch (const std::runtime_error &e) {
    EXPECT_NE(std::string(e.what()).find(".images, line 2"), std::string::npos) << e.what();
  }
  std::remove((path + ".sys").c_str());
  std::remove((path + ".lambda").c_str());
  std::remove((path + ".images").c_str());
}

// A pile at rest (examples/material, N 350, the end of its settling: 710 contacts, exported
// under the default with its floor of 10 sweeps). The error estimate is met after 6 sweeps,
// with the impulses within tol but the rotations far off; min_sweeps' floor brings them in.
TEST(AccuracyStudy, FloorOfSweepsBringsInTheRotationsOfAPileAtRest)
{
  const StepState st = read_step_state(std::string(FIBRE_TEST_DATA_DIR) + "/material350_settled");
  ASSERT_EQ(st.sys.num_contacts(), 710);
  const Reference ref = nonsmooth_reference(st.sys, st.lambda);
  ASSERT_TRUE(ref.confirmed()) << ref.agreement.velocity() << " " << ref.agreement.impulse();
  const double tk = k_product_seconds(st.sys, 5);
  const StepOptions floor = parse_settings({}).step;
  ASSERT_EQ(floor.min_sweeps, 10);
  StepOptions none = floor;
  none.min_sweeps = 0;
  none.focus_sweeps = 0; // plain sweeps stop on the estimate alone (focused ones on a full one)
  none.anderson = 0;     // and on the plain rate (Anderson starts at the floor)
  const StudyRow with = measure_setting(st, floor, ref.lambda, tk, 1);
  const StudyRow without = measure_setting(st, none, ref.lambda, tk, 1);
  // measured: 6 sweeps leave the rotations 9.8e-2 off, 10 sweeps 1.3e-2 (normal impulses 2.4e-6
  // and 3.0e-7)
  EXPECT_LT(without.sweeps, 10);
  EXPECT_EQ(with.sweeps, 10);
  EXPECT_LT(without.error.lambda_n, 1e-4);
  EXPECT_GT(without.error.dv_rot, 3e-2);
  EXPECT_LT(with.error.dv_rot, 2e-2);
  EXPECT_LT(with.error.dv_rot, 0.25 * without.error.dv_rot);
}

// A step where Anderson's combination cycles and plain sweeps converge (the LIGGGHTS heap of
// examples/liggghts/heap, step 374, feeding: 161 bodies, 48 contacts on and above the mesh
// plate, exported under the default). Without a way out the sweeps left the rotations 197% off
// after 1902 sweeps (within 2.7e-3 at sweep 900, then drifting off; "the run's own impulses"
// below). After kAndersonStallSweeps sweeps without a new smallest change they go on plain
// from the best checkpointed sweep, and converge (measured without restarts: 1735 sweeps,
// rotations 6.9e-4, normal impulses 1.2e-5). The default predicts the slow solve at sweep 30
// and starts it again: 193 sweeps, translations 7.4e-6, rotations 4.8e-3, normal impulses
// 2.6e-5, tangential 8.0e-4 (the rule bounds the impulses' error relative to |lambda| by tol).
TEST(AccuracyStudy, AndersonFallsBackToPlainSweepsWhereItsCombinationCycles)
{
  const StepState st = read_step_state(std::string(FIBRE_TEST_DATA_DIR) + "/liggghts_heap_step374");
  ASSERT_EQ(st.sys.num_contacts(), 48);
  const Reference ref = nonsmooth_reference(st.sys, st.lambda);
  ASSERT_TRUE(ref.newton.converged);
  EXPECT_LT(ref.agreement.velocity(), 1e-6); // the sweeps' reference agrees with Newton's
  const StepAccuracy run = step_accuracy(st.sys, st.lambda, ref.lambda);
  EXPECT_GT(run.dv_rot, 1.0);
  const double tk = k_product_seconds(st.sys, 5);
  const StudyRow stall =
      measure_setting(st, parse_settings({"restart_sweeps", "0"}).step, ref.lambda, tk, 1);
  EXPECT_TRUE(stall.converged);
  EXPECT_EQ(stall.slow_restarts, 0);
  EXPECT_GT(stall.sweeps, kAndersonStallSweeps); // it did stall
  EXPECT_LT(stall.error.dv_rot, 1e-2);
  EXPECT_LT(stall.error.dv_trans, 1e-4);
  EXPECT_LT(stall.error.lambda_n, 1e-3);
  const StudyRow def = measure_setting(st, parse_settings({}).step, ref.lambda, tk, 1);
  EXPECT_TRUE(def.converged);
  EXPECT_EQ(def.slow_restarts, 1);
  EXPECT_LT(4 * def.sweeps, stall.sweeps);
  EXPECT_LT(def.error.dv_rot, 1e-2);
  EXPECT_LT(def.error.dv_trans, 1e-4);
  EXPECT_LT(def.error.lambda_n, 1e-4);
  EXPECT_LT(def.error.lambda_t, 1e-3);
  // the rolling impulses are 1.3e-4 of |lambda|: 17% of them (measured) is 2.3e-5 of |lambda|
  EXPECT_LT(def.error.lambda_roll, 0.3);
}

// Steps whose sweeps are not slow never start again, and are solved bit for bit as without
// the rule: a settled pile and a pouring one.
TEST(AccuracyStudy, SweepsThatAreNotSlowDoNotStartAgain)
{
  for (const char *name : {"material350_settled", "material350_step600"}) {
    const StepState st = read_step_state(std::string(FIBRE_TEST_DATA_DIR) + "/" + name);
    const StepOptions def = parse_settings({}).step;
    StepOptions never = def;
    never.restart_sweeps = 0;
    ContactSystem sa = st.sys, sb = st.sys;
    const StepResult a = solve_step(sa, st.exchange(), def, &st.warm, MPI_COMM_SELF);
    const StepResult b = solve_step(sb, st.exchange(), never, &st.warm, MPI_COMM_SELF);
    EXPECT_TRUE(a.converged) << name;
    EXPECT_EQ(a.slow_restarts, 0) << name;
    EXPECT_EQ(a.sweeps, b.sweeps) << name;
    EXPECT_EQ((a.lambda - b.lambda).norm(), 0.0) << name;
  }
}

// A stiff pile's step (material deck, N 350, E = 1e8, seed 12, step 1158) whose sweeps go a
// thousand sweeps without a new smallest change while a wedged sphere works its way out, and
// then converge. The run that exported it (under a former stagnation rule) stopped
// after 1,385 sweeps with the rotations 16% off; under the accuracy rule only the cap ends the
// sweeps now.
TEST(AccuracyStudy, StiffPileStepConvergesPastAThousandSweepsWithoutANewSmallestChange)
{
  const StepState st =
      read_step_state(std::string(FIBRE_TEST_DATA_DIR) + "/material350_e1e8_step1158");
  ASSERT_EQ(st.sys.num_contacts(), 662);
  const Reference ref = nonsmooth_reference(st.sys, st.lambda);
  ASSERT_TRUE(ref.newton.converged);
  EXPECT_LT(ref.agreement.velocity(), 1e-6);
  const StepAccuracy run = step_accuracy(st.sys, st.lambda, ref.lambda);
  EXPECT_GT(run.dv_rot, 0.1); // the stagnated step of the export
  const double tk = k_product_seconds(st.sys, 5);
  const StepOptions defaults = parse_settings({}).step;
  const StudyRow def = measure_setting(st, defaults, ref.lambda, tk, 1);
  EXPECT_TRUE(def.converged);
  EXPECT_GT(def.sweeps, 1000);            // 1,848 here, 1,849 one contact at a time
  EXPECT_LE(def.sweeps, defaults.sweeps); // converged before the cap
  EXPECT_LT(def.error.dv_trans, 1e-4);
  EXPECT_LT(def.error.dv_rot, 1e-3);
  EXPECT_LT(def.error.lambda_n, 1e-3);
  EXPECT_LT(def.error.lambda_t, 1e-3);
}

// A cold start: the first step of the fix taking over a native pile (bench/takeover_state.py:
// tests/data/pile400.dump at E = 1e8, Mindlin mu 0.5, rigid rows; 1,084 contacts, no warm
// start). The default's sweeps meet tol against the converged step (measured 409 sweeps after
// a restart at sweep 30, velocity 5.8e-5, normal impulses 2.9e-5; 483 without). solver cg's linear
// pass leads its sweeps to another exact solution of the frictional step (complementarity
// 7e-13, 1.9e-2 from the reference in translational velocity and 4.8e-2 in rotational; exported
// with mu 0 both end within 3e-5 of it in translational velocity): Coulomb friction's step need not
// have one solution.
TEST(AccuracyStudy, TakeOverOfANativePileFromAColdStart)
{
  const StepState st = read_step_state(std::string(FIBRE_TEST_DATA_DIR) + "/pile400_takeover");
  ASSERT_EQ(st.sys.num_contacts(), 1084);
  ASSERT_EQ(st.warm.norm(), 0.0);
  const Reference ref = nonsmooth_reference(st.sys, st.lambda);
  ASSERT_TRUE(ref.confirmed()) << ref.agreement.velocity() << " " << ref.agreement.impulse();
  const StudyRow def = measure_setting(st, parse_settings({}).step, ref.lambda, 1.0, 1);
  EXPECT_TRUE(def.converged);
  EXPECT_GT(def.sweeps, 200); // a slow step
  EXPECT_LT(def.error.lambda_n, 1.5e-4);
  EXPECT_LT(def.error.velocity(), 3e-4);
  EXPECT_LT(def.error.impulse(), 1e-3);
  const StudyRow cg = measure_setting(
      st,
      parse_settings({"solver", "cg", "tol", "none", "sweeps", "5000", "sweep_tol", "1e-12"}).step,
      ref.lambda, 1.0, 1);
  std::printf("solver cg, swept to 1e-12: complementarity %.2g, velocity %.3g from the reference\n",
              cg.complementarity, cg.error.velocity());
  EXPECT_LT(cg.complementarity, 1e-10);
  EXPECT_LT(cg.error.velocity(), 0.1);
}
