// fibre/analysis.hpp (what fibre_analyze computes) called in-process on systems made here,
// its returned histories, spectra and CSV writers checked against the same quantities
// recomputed through the library API, with an independent dense reference for the exact
// velocities. Two tests run the fibre_analyze program itself: its argument and input errors,
// and one short run whose printed summary must be the library's.
//
// The tool is found next to this test in the build tree (<build>/tools/fibre_analyze, from
// <build>/tests/test_fibre_analyze), or where the environment variable FIBRE_ANALYZE says. It
// is started with posix_spawn and an environment without Open MPI's and PMIx's variables: this
// process is an MPI singleton itself, and a child must not take its launch data for its own.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/SparseCholesky>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "fibre/algebra/assembly.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/io/system_io.hpp"
#include "fibre/precond/preconditioner_family.hpp"
#include "fibre/scenes.hpp"
#include "fibre/solvers/krylov.hpp"
#include "fibre/study/analysis.hpp"
#include "fibre/study/spectra.hpp"
#include "reference.hpp"

extern char **environ;

using namespace fibre;
namespace fs = std::filesystem;

namespace {

const PrecondKind kPreconds[] = {PrecondKind::none, PrecondKind::jacobi, PrecondKind::block,
                                 PrecondKind::fibre, PrecondKind::tree};
const Method kMethods[] = {Method::cg, Method::cr, Method::minres};
constexpr double kTarget = 1e-6; // the tool's "to_1e-6" column

fs::path build_dir()
{
  return fs::read_symlink("/proc/self/exe").parent_path().parent_path();
}

fs::path tool_path()
{
  if (const char *env = std::getenv("FIBRE_ANALYZE")) return env;
  return build_dir() / "tools" / "fibre_analyze";
}

struct ToolResult {
  int status = -1; // exit status, -1: did not exit normally
  std::string out, err;
};

std::string slurp(const fs::path &p)
{
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool launch_variable(const std::string &entry)
{
  for (const char *prefix : {"OMPI_", "PMIX_", "ORTE_", "OPAL_"})
    if (entry.rfind(prefix, 0) == 0) return true;
  return false;
}

// Runs the tool with `args`; its stdout and stderr go to files in `dir`.
ToolResult run_tool(const std::vector<std::string> &args, const fs::path &dir)
{
  const std::string tool = tool_path().string();
  const fs::path out = dir / "tool.stdout", err = dir / "tool.stderr";
  std::vector<std::string> argv_s{tool};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char *> argv;
  for (std::string &a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_s;
  for (char **e = environ; *e; ++e)
    if (!launch_variable(*e)) env_s.emplace_back(*e);
  std::vector<char *> envp;
  for (std::string &e : env_s) envp.push_back(e.data());
  envp.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, tool.c_str(), &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  ToolResult res;
  if (rc != 0) {
    res.err = "posix_spawn failed: " + std::string(std::strerror(rc));
    return res;
  }
  int wstatus = 0;
  if (waitpid(pid, &wstatus, 0) == pid && WIFEXITED(wstatus)) res.status = WEXITSTATUS(wstatus);
  res.out = slurp(out);
  res.err = slurp(err);
  return res;
}

// A fresh scratch directory, removed again with the object.
struct ScratchDir {
  fs::path path;
  explicit ScratchDir(const std::string &name)
      : path(fs::temp_directory_path() / (name + "." + std::to_string(getpid())))
  {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~ScratchDir()
  {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

// ---- the analysis' results ----

using Key = std::string; // "form/precond/method"
Key key(Form f, const std::string &precond, Method m)
{
  return std::string(to_string(f)) + "/" + precond + "/" + to_string(m);
}
Key key(Form f, PrecondKind k, Method m)
{
  return key(f, to_string(k), m);
}

std::map<Key, const Run *> runs_by_key(const Analysis &an)
{
  std::map<Key, const Run *> out;
  for (const Run &r : an.runs) out[key(r.form, r.precond, r.method)] = &r;
  return out;
}

const SpectrumRun *find_spectrum(const Analysis &an, Form form, const std::string &precond)
{
  for (const SpectrumRun &s : an.spectra)
    if (s.form == form && s.precond == precond) return &s;
  return nullptr;
}

// The eigenvalues as write_spectrum writes them (comment lines skipped).
std::vector<double> written_eigenvalues(const SpectrumRun &run)
{
  std::stringstream file;
  write_spectrum(file, run);
  std::vector<double> ev;
  std::string line;
  while (std::getline(file, line))
    if (!line.empty() && line[0] != '#') ev.push_back(std::stod(line));
  return ev;
}

// ---- parsing the tool's output ----

struct SummaryRow {
  int iterations = 0;
  std::string stop, to_target;
};

// The rows of the "== <form> form runs" tables.
std::map<Key, SummaryRow> parse_summary(const std::string &out)
{
  std::map<Key, SummaryRow> rows;
  std::istringstream in(out);
  std::string line, form;
  bool in_table = false;
  while (std::getline(in, line)) {
    if (line.rfind("== ", 0) == 0) {
      std::istringstream h(line.substr(3));
      std::string f, word2, word3;
      h >> f >> word2 >> word3;
      in_table = word2 == "form" && word3 == "runs";
      form = f;
      continue;
    }
    if (!in_table || line.empty()) {
      in_table = in_table && !line.empty();
      continue;
    }
    std::istringstream t(line);
    std::string precond, method, rr, rb, ve, ve_rel, best;
    SummaryRow row;
    t >> precond >> method;
    if (precond == "precond") continue; // column header
    t >> row.iterations >> row.stop >> rr >> rb >> ve >> ve_rel >> best >> row.to_target;
    if (t) rows[form + "/" + precond + "/" + method] = row;
  }
  return rows;
}

// kappa_e per "form/precond" from the kappa table.
std::map<std::string, double> parse_kappa(const std::string &out)
{
  std::map<std::string, double> kappa;
  std::istringstream in(out);
  std::string line;
  bool in_table = false;
  while (std::getline(in, line)) {
    if (line.rfind("== kappa_e", 0) == 0) in_table = true;
    if (!in_table) continue;
    std::istringstream t(line);
    std::string form, precond;
    long n = 0;
    double ke = 0;
    if ((t >> form >> precond >> n >> ke) && (form == "contact" || form == "body"))
      kappa[form + "/" + precond] = ke;
  }
  return kappa;
}

struct CsvRow {
  double rr = 0, rb = 0, ve = 0, ve_rel = 0;
};

// The history CSV: comment lines (#), the header, then one row per iteration.
std::map<Key, std::vector<CsvRow>> read_history(std::istream &in, std::string &header,
                                                std::map<std::string, long> &sizes)
{
  std::map<Key, std::vector<CsvRow>> runs;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("# size ", 0) == 0) {
      std::istringstream t(line.substr(7));
      std::string form;
      long n = 0;
      t >> form >> n;
      sizes[form] = n;
      continue;
    }
    if (line.empty() || line[0] == '#') continue;
    if (header.empty()) {
      header = line;
      continue;
    }
    std::vector<std::string> f;
    std::stringstream s(line);
    std::string cell;
    while (std::getline(s, cell, ',')) f.push_back(cell);
    if (f.size() != 8) {
      ADD_FAILURE() << "bad CSV line: " << line;
      continue;
    }
    std::vector<CsvRow> &run = runs[f[0] + "/" + f[2] + "/" + f[1]];
    EXPECT_EQ(std::stoi(f[3]), static_cast<int>(run.size())) << line;
    run.push_back({std::stod(f[4]), std::stod(f[5]), std::stod(f[6]), std::stod(f[7])});
  }
  return runs;
}

// ---- the same runs through the library ----

struct LibraryRun {
  SolveResult result;
  std::vector<CsvRow> rows;
  int to_target = -1; // iterations to ve_rel <= kTarget, -1: not reached
};

// dv* from the dense K of reference.hpp (independent of the library's kernels and of MUMPS).
Vector dense_reference_dv(const ContactSystem &sys)
{
  const test::Dense G = test::dense_G(sys);
  const Vector Sinv_b = sys.rhs().cwiseQuotient(test::dense_sigma(sys));
  return test::dense_K(sys).llt().solve(G.transpose() * Sinv_b);
}

LibraryRun library_run(const ContactSystem &sys, Form form, PrecondKind kind, Method method,
                       int maxiter, const Vector &dv_ref, double norm_A)
{
  const Exchange &ex = serial_exchange();
  const auto A = make_operator(form, sys, ex);
  PrecondOptions po;
  po.kind = kind;
  const auto P = make_preconditioner(form, sys, ex, po);
  const Vector rhs = form == Form::body ? body_rhs(sys, ex, sys.rhs()) : sys.rhs();
  LibraryRun run;
  KrylovMonitor mon;
  mon.record_history = true;
  mon.velocity_error = [&](const Vector &x) {
    Vector Ax;
    A->apply(x, Ax);
    const double r = (rhs - Ax).norm();
    const Vector dv = form == Form::body ? x : body_from_lambda(sys, ex, x);
    const double ve = (dv - dv_ref).norm();
    run.rows.push_back({r / norm_A, r / rhs.norm(), ve, ve / dv_ref.norm()});
    return ve;
  };
  StopControl stop;
  stop.tol = 0;
  stop.max_iter = maxiter;
  Vector x = Vector::Zero(A->size());
  run.result = krylov_solve(method, *A, *P, rhs, x, stop, &mon);
  for (std::size_t k = 0; k < run.rows.size(); ++k)
    if (run.rows[k].ve_rel <= kTarget) {
      run.to_target = static_cast<int>(k);
      break;
    }
  return run;
}

ContactSystem small_pile()
{
  SceneParams p;
  ContactSystem sys = pile_scene(40, p);
  sys.set_rhs(spook_rhs(sys));
  return sys;
}

// The analysis' run against the test's own: same iterations, stop and iterations to kTarget.
void expect_same_run(const fibre::Run &run, const LibraryRun &lib)
{
  EXPECT_EQ(run.result.iterations, lib.result.iterations);
  EXPECT_EQ(run.result.reason, lib.result.reason);
  EXPECT_EQ(iterations_to(run, kTarget), lib.to_target);
}

ContactSystem small_pile_prepared()
{
  return prepare_system(small_pile()).system;
}

std::string target_text(int k)
{
  return k >= 0 ? std::to_string(k) : "-";
}

} // namespace

// Every form x method x preconditioner on a 40-sphere pile: the returned runs and their history
// CSV (write_history_csv) against the test's own runs, and the spectra (write_spectrum) against
// dense ones. Formerly parsed from the tool's printed summary and files.
TEST(FibreAnalyze, SummaryCsvAndSpectraMatchTheLibrary)
{
  const ContactSystem sys = small_pile_prepared();
  AnalysisOptions opt;
  opt.spectra = true; // automatic: dense at this size
  const Analysis an = analyze(sys, opt);
  ASSERT_FALSE(an.zero_rhs);

  // Default maxiter: the system size of each form.
  std::stringstream csv_text;
  write_history_csv(csv_text, an, "pile40.sys", 1.0);
  std::string header;
  std::map<std::string, long> sizes;
  const auto csv = read_history(csv_text, header, sizes);
  EXPECT_EQ(header, "form,method,precond,iteration,rr,rb,ve,ve_rel");
  EXPECT_EQ(sizes["contact"], long(sys.contact_dofs()));
  EXPECT_EQ(sizes["body"], long(sys.body_dofs()));

  const auto runs = runs_by_key(an);
  EXPECT_EQ(runs.size(), 30u);
  const Vector dv_ref = dense_reference_dv(sys);
  int reached = 0;
  for (Form form : {Form::contact, Form::body}) {
    const double norm_A =
        form == Form::contact ? test::dense_A(sys).norm() : test::dense_K(sys).norm();
    const int maxiter =
        static_cast<int>(form == Form::contact ? sys.contact_dofs() : sys.body_dofs());
    for (PrecondKind kind : kPreconds)
      for (Method m : kMethods) {
        const Key k = key(form, kind, m);
        SCOPED_TRACE(k);
        ASSERT_TRUE(runs.count(k));
        ASSERT_TRUE(csv.count(k));
        const LibraryRun lib = library_run(sys, form, kind, m, maxiter, dv_ref, norm_A);
        const fibre::Run &run = *runs.at(k);
        const std::vector<CsvRow> &hist = csv.at(k);
        expect_same_run(run, lib);
        reached += lib.to_target >= 0;
        ASSERT_EQ(hist.size(), lib.rows.size());
        // The iterates are the same computation; only ||A||_F and dv* are computed otherwise.
        const std::size_t at = std::min<std::size_t>(100, hist.size() - 1);
        const double floor = 1e-11 * dv_ref.norm();
        for (std::size_t i : {std::size_t(0), std::size_t(1), at, hist.size() - 1}) {
          EXPECT_NEAR(hist[i].rr, lib.rows[i].rr, 1e-8 * lib.rows[i].rr) << "iteration " << i;
          EXPECT_NEAR(hist[i].rb, lib.rows[i].rb, 1e-8 * lib.rows[i].rb) << "iteration " << i;
          EXPECT_NEAR(hist[i].ve, lib.rows[i].ve, 1e-8 * lib.rows[i].ve + floor)
              << "iteration " << i;
          EXPECT_NEAR(hist[i].ve_rel, lib.rows[i].ve_rel,
                      1e-8 * lib.rows[i].ve_rel + floor / dv_ref.norm())
              << "iteration " << i;
        }
      }
  }
  EXPECT_GE(reached, 5) << "too few runs reach the target for the check to mean much";

  // Spectra: one per form x preconditioner, all eigenvalues (dense at this size), kappa_e
  // equal to the library's.
  EXPECT_EQ(an.spectra.size(), 10u);
  for (Form form : {Form::contact, Form::body}) {
    const auto A = make_operator(form, sys, serial_exchange());
    for (PrecondKind kind : kPreconds) {
      SCOPED_TRACE(std::string(to_string(form)) + "_" + to_string(kind));
      const SpectrumRun *run = find_spectrum(an, form, to_string(kind));
      ASSERT_NE(run, nullptr) << "missing spectrum";
      EXPECT_TRUE(run->complete);
      const std::vector<double> ev = written_eigenvalues(*run);
      EXPECT_EQ(static_cast<Eigen::Index>(ev.size()), A->size());
      PrecondOptions po;
      po.kind = kind;
      const Spectrum s = dense_spectrum(*A, *make_preconditioner(form, sys, serial_exchange(), po));
      EXPECT_NEAR(run->s.kappa_e, s.kappa_e, 1e-3 * s.kappa_e);
      EXPECT_NEAR(effective_condition(ev).kappa_e, s.kappa_e, 1e-9 * s.kappa_e);
    }
  }
  // The unpreconditioned contact form against the independent dense A.
  Eigen::SelfAdjointEigenSolver<test::Dense> es(test::dense_A(sys), Eigen::EigenvaluesOnly);
  const Vector ev = es.eigenvalues();
  const double ke = effective_condition({ev.data(), ev.data() + ev.size()}).kappa_e;
  EXPECT_NEAR(find_spectrum(an, Form::contact, "none")->s.kappa_e, ke, 1e-3 * ke);
}

TEST(FibreAnalyze, SigmaScaleChangesSigmaOnly)
{
  const ContactSystem sys = small_pile();
  const double scale = 1e-3;
  const ContactSystem prepared = prepare_system(sys, scale).system;
  // The same system with every compliance scaled, by hand.
  std::vector<Contact> contacts = sys.contacts();
  for (Contact &c : contacts)
    for (double &eps : c.compliance) eps *= scale;
  ContactSystem scaled(sys.bodies(), contacts, sys.rows(), sys.params());
  scaled.set_rhs(sys.rhs());
  EXPECT_NEAR(scaled.sigma()[0], scale * sys.sigma()[0], 1e-15 * sys.sigma()[0]);
  EXPECT_EQ((prepared.sigma() - scaled.sigma()).norm(), 0.0);
  EXPECT_EQ((prepared.rhs() - sys.rhs()).norm(), 0.0);

  AnalysisOptions opt;
  opt.forms = {Form::body};
  opt.preconds = {PrecondKind::block};
  opt.methods = {Method::cr};
  opt.maxiter = 120;
  opt.spectra = true;
  opt.kappa_method = KappaMethod::dense;
  const Analysis an = analyze(prepared, opt);
  ASSERT_EQ(an.runs.size(), 1u);
  const LibraryRun lib = library_run(scaled, Form::body, PrecondKind::block, Method::cr, 120,
                                     dense_reference_dv(scaled), test::dense_K(scaled).norm());
  EXPECT_EQ(iterations_to(an.runs[0], kTarget), lib.to_target);
  EXPECT_EQ(an.runs[0].result.iterations, lib.result.iterations);
  PrecondOptions po;
  po.kind = PrecondKind::block;
  const Spectrum s =
      dense_spectrum(BodySpaceOperator(scaled, serial_exchange()),
                     *make_preconditioner(Form::body, scaled, serial_exchange(), po));
  ASSERT_EQ(an.spectra.size(), 1u);
  EXPECT_NEAR(an.spectra[0].s.kappa_e, s.kappa_e, 1e-3 * s.kappa_e);
}

// Formerly read from the tool's printed description ("3 ghost bodies", "(N masked)").
TEST(FibreAnalyze, GhostsAndMaskedRows)
{
  ScratchDir dir("fibre_analyze_ghosts");
  SceneParams p;
  const ContactSystem pile = pile_scene(30, p);
  ContactSystem sys(pile.bodies(), pile.contacts(), 6, p.spook, pile.num_bodies() - 3);
  std::vector<unsigned char> mask(sys.contact_dofs(), 1);
  for (std::size_t r = 4; r < mask.size(); r += 6) mask[r] = 0; // no rolling on axis t1
  sys.set_row_mask(mask);
  sys.set_rhs(spook_rhs(sys));
  const fs::path file = dir.path / "ghosts.sys";
  write_system_file(file.string(), sys);
  const AnalysisSystem in = prepare_system(read_system_file(file.string()));
  EXPECT_EQ(in.ghosts, 3);
  EXPECT_EQ(in.system.num_owned_bodies(), in.system.num_bodies());
  EXPECT_EQ(summarize(in.system).masked_rows, long(sys.num_contacts()));
  AnalysisOptions opt;
  opt.maxiter = 50;
  opt.spectra = true;
  const Analysis an = analyze(in.system, opt);
  EXPECT_EQ(runs_by_key(an).size(), 30u);
  EXPECT_EQ(an.spectra.size(), 10u);
}

TEST(FibreAnalyzeTool, BadArgumentsAndInputsExitWithStatus2)
{
  ASSERT_TRUE(fs::exists(tool_path())) << "fibre_analyze not found at " << tool_path()
                                       << " (build the target, or set FIBRE_ANALYZE)";
  ScratchDir dir("fibre_analyze_bad");
  const fs::path good = dir.path / "good.sys";
  write_system_file(good.string(), small_pile());
  const fs::path garbage = dir.path / "garbage.sys";
  std::ofstream(garbage) << "fibre_contact_system 1\nrows 7\n";
  const std::string g = good.string();
  const struct {
    std::vector<std::string> args;
    const char *message;
  } cases[] = {
      {{}, "no system file"},
      {{g, g}, "more than one system file"},
      {{g, "--bogus"}, "unknown option '--bogus'"},
      {{g, "-x"}, "unknown option '-x'"},
      {{g, "--maxiter"}, "--maxiter needs a value"},
      {{g, "--maxiter", "0"}, "--maxiter needs a positive integer"},
      {{g, "--maxiter=12x"}, "--maxiter needs a positive integer"},
      {{g, "--form", "dual"}, "unknown form 'dual'"},
      {{g, "--methods", "uzawa,,cr"}, "empty entry"},
      {{g, "--methods", "gmres"}, "unknown entry 'gmres'"},
      {{g, "--precond", "block,ilu"}, "unknown entry 'ilu'"},
      {{g, "--weight", "mass"}, "unknown weight 'mass'"},
      {{g, "--kappa", "exact"}, "unknown method 'exact'"},
      {{g, "--sigma-scale", "-1"}, "--sigma-scale needs a positive finite number"},
      {{g, "--sigma-scale", "inf"}, "--sigma-scale needs a positive finite number"},
      {{g, "--combine", "add_fibre_tree,jacobi"}, "--combine: unknown entry 'jacobi'"},
      {{g, "--lanczos-steps", "0"}, "--lanczos-steps needs a positive integer"},
      {{(dir.path / "missing.sys").string()}, "missing.sys"},
      {{garbage.string()}, "line 2"},
      {{g, "--csv", (dir.path / "no/such/dir/h.csv").string()}, "cannot write"},
      {{g, "--spectra", (dir.path / "no/such/dir/s").string()}, "cannot write"},
  };
  for (const auto &c : cases) {
    std::string joined;
    for (const std::string &a : c.args) joined += " " + a;
    SCOPED_TRACE("fibre_analyze" + joined);
    const ToolResult res = run_tool(c.args, dir.path);
    EXPECT_EQ(res.status, 2) << res.out << res.err;
    EXPECT_NE(res.err.find(c.message), std::string::npos) << res.err;
    EXPECT_EQ(res.err.find("error:"), std::string::npos) << "not a computation failure";
  }
  const ToolResult help = run_tool({"--help"}, dir.path);
  EXPECT_EQ(help.status, 0);
  EXPECT_NE(help.out.find("usage: fibre_analyze SYSTEM_FILE"), std::string::npos);
}

// One short run of the program: its printed summary must be the library's, its files written.
TEST(FibreAnalyzeTool, ShortRunPrintsTheLibrarysResults)
{
  ScratchDir dir("fibre_analyze_small");
  const ContactSystem sys = small_pile();
  const fs::path file = dir.path / "pile40.sys";
  write_system_file(file.string(), sys);
  const ToolResult res = run_tool({file.string(), "--form", "body", "--maxiter", "40", "--methods",
                                   "uzawa,cr", "--csv", (dir.path / "hist.csv").string(),
                                   "--spectra", (dir.path / "spec").string()},
                                  dir.path);
  ASSERT_EQ(res.status, 0) << res.out << res.err;
  EXPECT_NE(res.out.find("Frobenius"), std::string::npos) << "the norm of A must be stated";

  AnalysisOptions opt;
  opt.forms = {Form::body};
  opt.methods = {Method::cg, Method::cr};
  opt.maxiter = 40;
  opt.spectra = true;
  const AnalysisSystem in = prepare_system(read_system_file(file.string()));
  const Analysis an = analyze(in.system, opt);
  const auto summary = parse_summary(res.out);
  ASSERT_EQ(summary.size(), 10u) << res.out;
  for (const auto &[k, run] : runs_by_key(an)) {
    SCOPED_TRACE(k);
    ASSERT_TRUE(summary.count(k)) << res.out; // "cg", not "uzawa"
    EXPECT_EQ(summary.at(k).iterations, run->result.iterations);
    EXPECT_EQ(summary.at(k).stop, to_string(run->result.reason));
    EXPECT_EQ(summary.at(k).to_target, target_text(iterations_to(*run, kTarget)));
  }
  const auto kappa = parse_kappa(res.out);
  EXPECT_EQ(kappa.size(), 5u) << res.out;
  for (const SpectrumRun &s : an.spectra) {
    EXPECT_NEAR(kappa.at("body/" + s.precond), s.s.kappa_e, 1e-3 * s.s.kappa_e); // 4 digits
    EXPECT_TRUE(fs::exists(dir.path / ("spec_body_" + s.precond + ".csv"))) << s.precond;
  }
  EXPECT_TRUE(fs::exists(dir.path / "spec_kappa.csv"));
  std::ifstream hist(dir.path / "hist.csv");
  std::string header;
  std::map<std::string, long> sizes;
  EXPECT_EQ(read_history(hist, header, sizes).size(), 10u);
  EXPECT_EQ(header, "form,method,precond,iteration,rr,rb,ve,ve_rel");
  EXPECT_EQ(sizes["body"], long(sys.body_dofs()));
}

// The LAMMPS-poured pile (tests/data/pile400.dump): the body form reaches ve_rel <= 1e-6 in
// 33-57 iterations whatever the preconditioner (doc/convergence_pile400.txt). The system file
// is left in <build>/tests/fibre_analyze/pile400.sys for fibre_analyze runs by hand
// (examples/thesis/plot_convergence.py).
TEST(FibreAnalyze, LammpsPileBodyFormAgreesWithTheLibrary)
{
  ContactSystem pile = lammps_pile_scene(FIBRE_TEST_DATA_DIR "/pile400.dump", SceneParams{});
  pile.set_rhs(spook_rhs(pile));
  const fs::path out_dir = build_dir() / "tests" / "fibre_analyze";
  fs::create_directories(out_dir);
  write_system_file((out_dir / "pile400.sys").string(), pile);
  AnalysisOptions opt;
  opt.forms = {Form::body};
  opt.maxiter = 100;
  const AnalysisSystem in = prepare_system(pile);
  const Analysis an = analyze(in.system, opt);
  const auto runs = runs_by_key(an);
  ASSERT_EQ(runs.size(), 15u);

  // Reference velocities from a sparse Cholesky of the library's assembled K.
  Eigen::SimplicialLLT<SparseMatrix> llt(assemble_K(pile));
  ASSERT_EQ(llt.info(), Eigen::Success);
  const Vector dv_ref = llt.solve(body_rhs(pile, serial_exchange(), pile.rhs()));
  const double norm_K = assemble_K(pile).norm();
  for (PrecondKind kind : kPreconds)
    for (Method m : kMethods) {
      const Key k = key(Form::body, kind, m);
      SCOPED_TRACE(k);
      const LibraryRun lib = library_run(pile, Form::body, kind, m, 100, dv_ref, norm_K);
      const int to_target = iterations_to(*runs.at(k), kTarget);
      EXPECT_EQ(to_target, lib.to_target);
      ASSERT_GE(to_target, 0);
      EXPECT_GE(to_target, 25);
      EXPECT_LE(to_target, 65);
    }
}

// ---- a system exported by fix fibre_contact from the material deck ----

namespace {

// Test-side twins of combined_preconditioner.hpp (independent of the library's).
class TestAverage final : public Preconditioner {
 public:
  TestAverage(std::unique_ptr<Preconditioner> a, std::unique_ptr<Preconditioner> b)
      : a_(std::move(a)), b_(std::move(b))
  {
  }
  void apply(const Vector &r, Vector &z) const override
  {
    Vector za, zb;
    a_->apply(r, za);
    b_->apply(r, zb);
    z = 0.5 * (za + zb);
  }
  std::string name() const override { return "test_average"; }

 private:
  std::unique_ptr<Preconditioner> a_, b_;
};

class TestSymmetricProduct final : public Preconditioner {
 public:
  TestSymmetricProduct(const LinearOperator &A, std::unique_ptr<Preconditioner> outer,
                       std::unique_ptr<Preconditioner> inner)
      : A_(A), o_(std::move(outer)), i_(std::move(inner))
  {
  }
  void apply(const Vector &r, Vector &z) const override
  {
    Vector Az, t;
    o_->apply(r, z);
    A_.apply(z, Az);
    i_->apply(r - Az, t);
    z += t;
    A_.apply(z, Az);
    o_->apply(r - Az, t);
    z += t;
  }
  std::string name() const override { return "test_product"; }

 private:
  const LinearOperator &A_;
  std::unique_ptr<Preconditioner> o_, i_;
};

// iterations to ve_rel <= kTarget (-1: not reached) with P on `form`.
int library_to_target(const ContactSystem &sys, Form form, const LinearOperator &A,
                      const Preconditioner &P, int maxiter, const Vector &dv_ref)
{
  const Exchange &ex = serial_exchange();
  const Vector rhs = form == Form::body ? body_rhs(sys, ex, sys.rhs()) : sys.rhs();
  int to_target = -1;
  int k = 0;
  KrylovMonitor mon;
  mon.record_history = true;
  mon.velocity_error = [&](const Vector &x) {
    const Vector dv = form == Form::body ? x : body_from_lambda(sys, ex, x);
    const double ve = (dv - dv_ref).norm();
    if (to_target < 0 && ve / dv_ref.norm() <= kTarget) to_target = k;
    ++k;
    return ve;
  };
  StopControl stop;
  stop.tol = 0;
  stop.max_iter = maxiter;
  Vector x = Vector::Zero(A.size());
  krylov_solve(Method::cg, A, P, rhs, x, stop, &mon);
  return to_target;
}

} // namespace

// tests/data/material350_step1000.sys: written by `fix fibre_contact ... export 200 snap` in
// examples/material/in.material at N = 350, step 1000 (the deck of commit dc68075: emitter at
// z 6-14, mu_roll 0.1): 341 bodies, 489 contacts (235 on the floor), compliances of the fix's
// auto rule. A fixed test input: later deck versions need not reproduce it. The analysis on it,
// both forms, every method and preconditioner and two combinations, against the same runs
// through the library with an independent sparse-Cholesky dv*.
TEST(FibreAnalyze, ExportedMaterialSystemMatchesTheLibrary)
{
  const ContactSystem sys = read_system_file(FIBRE_TEST_DATA_DIR "/material350_step1000.sys");
  ASSERT_EQ(sys.num_bodies(), 341);
  ASSERT_EQ(sys.num_owned_bodies(), 341);
  ASSERT_EQ(sys.num_contacts(), 489);
  constexpr int kMaxiter = 120;
  AnalysisOptions opt;
  opt.maxiter = kMaxiter;
  opt.combinations = {Combination::add_fibre_tree, Combination::mul_tree_fibre};
  const AnalysisSystem in = prepare_system(sys);
  const Analysis an = analyze(in.system, opt);
  const auto runs = runs_by_key(an);
  EXPECT_EQ(runs.size(), 2u * (15u + 6u));
  std::stringstream csv_text;
  write_history_csv(csv_text, an, "material350_step1000.sys", 1.0);
  std::string header;
  std::map<std::string, long> sizes;
  const auto csv = read_history(csv_text, header, sizes);
  EXPECT_EQ(sizes["contact"], 6L * 489);
  EXPECT_EQ(sizes["body"], 6L * 341);

  Eigen::SimplicialLLT<SparseMatrix> llt(assemble_K(sys));
  ASSERT_EQ(llt.info(), Eigen::Success);
  const Vector dv_ref = llt.solve(body_rhs(sys, serial_exchange(), sys.rhs()));
  const double floor = 1e-11 * dv_ref.norm();
  for (Form form : {Form::contact, Form::body}) {
    const double norm_A = form == Form::body ? assemble_K(sys).norm() : assemble_A(sys).norm();
    for (PrecondKind kind : kPreconds)
      for (Method m : kMethods) {
        const Key k = key(form, kind, m);
        SCOPED_TRACE(k);
        ASSERT_TRUE(runs.count(k));
        ASSERT_TRUE(csv.count(k));
        const LibraryRun lib = library_run(sys, form, kind, m, kMaxiter, dv_ref, norm_A);
        const fibre::Run &run = *runs.at(k);
        expect_same_run(run, lib);
        const std::vector<CsvRow> &hist = csv.at(k);
        ASSERT_EQ(hist.size(), lib.rows.size());
        const std::size_t at = std::min<std::size_t>(100, hist.size() - 1);
        EXPECT_NEAR(hist[at].rr, lib.rows[at].rr, 1e-8 * lib.rows[at].rr);
        EXPECT_NEAR(hist[at].ve_rel, lib.rows[at].ve_rel,
                    1e-8 * lib.rows[at].ve_rel + floor / dv_ref.norm());
      }
    // the body form converges on this export (Table "iterations to 1e-6" of RESULTS.md)
    if (form == Form::body) {
      const int tree = iterations_to(*runs.at(key(form, PrecondKind::tree, Method::cg)), kTarget);
      ASSERT_GE(tree, 0);
      EXPECT_LE(tree, 40);
    }
    // the combinations against the test's own combinations of the library's preconditioners
    const Exchange &ex = serial_exchange();
    const auto A = make_operator(form, sys, ex);
    auto build = [&](PrecondKind kind) {
      PrecondOptions po;
      po.kind = kind;
      return make_preconditioner(form, sys, ex, po);
    };
    const TestAverage avg(build(PrecondKind::fibre), build(PrecondKind::tree));
    const TestSymmetricProduct prod(*A, build(PrecondKind::tree), build(PrecondKind::fibre));
    const Key add = key(form, "add_fibre_tree", Method::cg);
    const Key mul = key(form, "mul_tree_fibre", Method::cg);
    ASSERT_TRUE(runs.count(add));
    ASSERT_TRUE(runs.count(mul));
    EXPECT_EQ(iterations_to(*runs.at(add), kTarget),
              library_to_target(sys, form, *A, avg, kMaxiter, dv_ref));
    EXPECT_EQ(iterations_to(*runs.at(mul), kTarget),
              library_to_target(sys, form, *A, prod, kMaxiter, dv_ref));
  }
}
