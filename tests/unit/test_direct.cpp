// MUMPS (direct.hpp) against dense Eigen Cholesky on the reference matrices, in both forms,
// serial and distributed over MPI ranks.
//
// The distributed cases need several ranks. Run alone (as ctest does), the test relaunches
// itself under `mpirun -np 2` and `-np 3` for the MPI cases and checks their exit status.
#include <gtest/gtest.h>
#include <mpi.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <string>

#include "fibre/algebra/spook.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/scenes.hpp"
#include "fibre/solvers/direct.hpp"
#include "fibre/study/spectra.hpp"
#include "reference.hpp"

using namespace fibre;

namespace {

using fibre::test::rel_diff;

int world_size()
{
  int n = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &n);
  return n;
}

int world_rank()
{
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

// Dense reference solution of A lambda = b.
Eigen::VectorXd dense_lambda(const ContactSystem &sys, const Eigen::VectorXd &b)
{
  const test::Dense A = test::dense_A(sys);
  Eigen::LLT<test::Dense> llt(A);
  EXPECT_EQ(llt.info(), Eigen::Success);
  return llt.solve(b);
}

Eigen::VectorXd velocities(const ContactSystem &sys, const Eigen::VectorXd &lambda)
{
  return test::dense_Minv(sys) * test::dense_G(sys).transpose() * lambda;
}

void expect_both_forms_match_dense(const ContactSystem &sys, double tol)
{
  const Vector b = sys.rhs();
  const Eigen::VectorXd ref = dense_lambda(sys, b);
  const Vector lc = direct_solve(Form::contact, sys, serial_exchange(), b, MPI_COMM_SELF);
  const Vector lb = direct_solve(Form::body, sys, serial_exchange(), b, MPI_COMM_SELF);
  EXPECT_LT(rel_diff(lc, ref), tol);
  EXPECT_LT(rel_diff(lb, ref), tol);
  // What moves the bodies: the forms agree on velocities far below the solve tolerance.
  EXPECT_LT(rel_diff(velocities(sys, lb), velocities(sys, lc)), 1e-10);
}

} // namespace

TEST(DistributedCholesky, SmallSpdMatrixFromMixedTriangles)
{
  // Random SPD matrix, given partly in the lower triangle and with split duplicates.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  const int n = 12;
  Eigen::MatrixXd B(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) B(i, j) = (std::abs(i - j) <= 2) ? u(rng) : 0.0;
  const Eigen::MatrixXd S = B * B.transpose() + Eigen::MatrixXd::Identity(n, n);
  std::vector<long> rows, cols;
  std::vector<double> vals;
  for (int i = 0; i < n; ++i)
    for (int j = i; j < n; ++j) {
      if (S(i, j) == 0.0) continue;
      const bool lower = (i + j) % 2 == 1;
      rows.push_back(lower ? j : i);
      cols.push_back(lower ? i : j);
      vals.push_back(0.25 * S(i, j));
      rows.push_back(i);
      cols.push_back(j);
      vals.push_back(0.75 * S(i, j));
    }
  DistributedCholesky chol(MPI_COMM_SELF);
  chol.factorize(n, rows, cols, vals);
  EXPECT_TRUE(chol.factorized());
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  std::vector<long> idx;
  std::vector<double> val;
  for (int i = 0; i < n; ++i) {
    // Split each rhs entry in two to check that they are summed.
    const double x = u(rng);
    rhs[i] = x;
    idx.insert(idx.end(), {long(i), long(i)});
    val.insert(val.end(), {0.5 * x, 0.5 * x});
  }
  const std::vector<long> wanted{11, 0, 5, 5, 3};
  const std::vector<double> x = chol.solve(idx, val, wanted);
  const Eigen::VectorXd ref = S.llt().solve(rhs);
  ASSERT_EQ(x.size(), wanted.size());
  for (std::size_t e = 0; e < wanted.size(); ++e)
    EXPECT_NEAR(x[e], ref[wanted[e]], 1e-12 * ref.norm()) << "index " << wanted[e];
}

TEST(DistributedCholesky, ErrorsBecomeExceptions)
{
  DistributedCholesky chol(MPI_COMM_SELF);
  // A singular matrix: the last row and column are zero.
  const std::vector<long> r{0, 1, 2}, c{0, 1, 1};
  const std::vector<double> v{2.0, 1.0, 0.0};
  try {
    chol.factorize(3, r, c, v);
    FAIL() << "singular matrix was factorized";
  } catch (const DirectSolverError &e) {
    EXPECT_LT(e.infog1(), 0);
    EXPECT_NE(std::string(e.what()).find("INFOG(1)"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(chol.factorized());
  EXPECT_THROW(chol.solve({0}, {1.0}, {0}), std::invalid_argument);
  EXPECT_THROW(chol.factorize(3, {0, 3}, {0, 0}, {1.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(chol.factorize(3, {0}, {0, 1}, {1.0}), std::invalid_argument);
  const std::vector<long> d{0, 1, 2};
  chol.factorize(3, d, d, {1.0, 2.0, 4.0});
  EXPECT_THROW(chol.solve({3}, {1.0}, {0}), std::invalid_argument);
  const std::vector<double> x = chol.solve({0, 1, 2}, {1.0, 1.0, 1.0}, {2, 1, 0});
  EXPECT_DOUBLE_EQ(x[0], 0.25);
  EXPECT_DOUBLE_EQ(x[1], 0.5);
  EXPECT_DOUBLE_EQ(x[2], 1.0);
}

TEST(DirectSolve, GridBothForms)
{
  SceneParams p;
  expect_both_forms_match_dense(grid_scene(p), 1e-10);
}

TEST(DirectSolve, PilesBothFormsWithGapTerm)
{
  for (std::uint64_t seed : {1u, 2u}) {
    SceneParams p;
    p.seed = seed;
    const ContactSystem sys = pile_scene(120, p);
    // spook_rhs with overlaps: the gap term is present and part of b lies in null(G^T).
    double gaps = 0;
    for (const Contact &c : sys.contacts()) gaps += std::abs(c.gap);
    ASSERT_GT(gaps, 0.0);
    expect_both_forms_match_dense(sys, 1e-8);
  }
  SceneParams p;
  p.rows = 3;
  expect_both_forms_match_dense(pile_scene(80, p), 1e-8);
}

TEST(DirectSolve, MaskedRowsSolveToZero)
{
  SceneParams p;
  ContactSystem sys = pile_scene(40, p);
  std::vector<unsigned char> mask(sys.contact_dofs(), 1);
  for (std::size_t r = 1; r < mask.size(); r += 4) mask[r] = 0;
  sys.set_row_mask(mask);
  sys.set_rhs(spook_rhs(sys));
  for (Form f : {Form::contact, Form::body}) {
    const Vector l = direct_solve(f, sys, serial_exchange(), sys.rhs(), MPI_COMM_SELF);
    for (std::size_t r = 1; r < mask.size(); r += 4) EXPECT_EQ(l[Eigen::Index(r)], 0.0);
    EXPECT_LT(rel_diff(l, dense_lambda(sys, sys.rhs())), 1e-8);
  }
}

TEST(DirectSolve, RejectsWrongRhsSize)
{
  SceneParams p;
  const ContactSystem sys = grid_scene(p);
  EXPECT_THROW(direct_solve(Form::contact, sys, serial_exchange(), Vector::Zero(3), MPI_COMM_SELF),
               std::invalid_argument);
}

// ---- Distributed: a real MPI exchange over a pile split between the ranks ----

namespace {

// Every rank builds the same scene; rank r owns the bodies of its x-slab and the contacts
// whose body a it owns. Ghosts are the other bodies its contacts touch. Halo traffic goes
// through dense global vectors (simple, and fine for a test).
class SlabExchange final : public Exchange {
 public:
  using Exchange::max;
  using Exchange::sum;
  SlabExchange(MPI_Comm comm, int total, std::vector<int> local_to_global, int owned)
      : comm_(comm), total_(total), l2g_(std::move(local_to_global)), owned_(owned)
  {
  }
  void forward(Vector &v) const override
  {
    Vector g = Vector::Zero(6 * Eigen::Index(total_));
    for (int i = 0; i < owned_; ++i) g.segment<6>(6 * l2g_[i]) = v.segment<6>(6 * i);
    MPI_Allreduce(MPI_IN_PLACE, g.data(), int(g.size()), MPI_DOUBLE, MPI_SUM, comm_);
    for (std::size_t i = owned_; i < l2g_.size(); ++i)
      v.segment<6>(6 * i) = g.segment<6>(6 * l2g_[i]);
  }
  void reverse_sum(Vector &v) const override
  {
    Vector g = Vector::Zero(6 * Eigen::Index(total_));
    for (std::size_t i = owned_; i < l2g_.size(); ++i) {
      g.segment<6>(6 * l2g_[i]) += v.segment<6>(6 * i);
      v.segment<6>(6 * i).setZero();
    }
    MPI_Allreduce(MPI_IN_PLACE, g.data(), int(g.size()), MPI_DOUBLE, MPI_SUM, comm_);
    for (int i = 0; i < owned_; ++i) v.segment<6>(6 * i) += g.segment<6>(6 * l2g_[i]);
  }
  void sum(double *x, int n) const override
  {
    MPI_Allreduce(MPI_IN_PLACE, x, n, MPI_DOUBLE, MPI_SUM, comm_);
  }
  void max(double *x, int n) const override
  {
    MPI_Allreduce(MPI_IN_PLACE, x, n, MPI_DOUBLE, MPI_MAX, comm_);
  }
  long exclusive_prefix_sum(long local) const override
  {
    long out = 0;
    MPI_Exscan(&local, &out, 1, MPI_LONG, MPI_SUM, comm_);
    int rank = 0;
    MPI_Comm_rank(comm_, &rank);
    return rank == 0 ? 0 : out;
  }

 private:
  MPI_Comm comm_;
  int total_;
  std::vector<int> l2g_;
  int owned_;
};

struct LocalPart {
  ContactSystem sys;
  std::vector<int> l2g;         // local body -> scene body
  std::vector<int> contact_ids; // local contact -> scene contact
};

LocalPart split(const ContactSystem &full, int rank, int nprocs)
{
  std::vector<double> xs;
  for (const Body &b : full.bodies()) xs.push_back(b.x.x());
  std::vector<double> sorted = xs;
  std::sort(sorted.begin(), sorted.end());
  auto slab = [&](int i) {
    const auto pos = std::upper_bound(sorted.begin(), sorted.end(), xs[i]) - sorted.begin() - 1;
    return std::min<int>(nprocs - 1, int(pos * nprocs / sorted.size()));
  };
  LocalPart part{ContactSystem(), {}, {}};
  std::map<int, int> g2l;
  for (int i = 0; i < full.num_bodies(); ++i)
    if (slab(i) == rank) {
      g2l[i] = int(part.l2g.size());
      part.l2g.push_back(i);
    }
  const int owned = int(part.l2g.size());
  std::vector<Contact> contacts;
  for (int c = 0; c < full.num_contacts(); ++c) {
    const Contact &k = full.contacts()[c];
    if (slab(k.a) != rank) continue;
    part.contact_ids.push_back(c);
    contacts.push_back(k);
    if (!k.is_wall() && !g2l.count(k.b)) {
      g2l[k.b] = int(part.l2g.size());
      part.l2g.push_back(k.b);
    }
  }
  for (Contact &k : contacts) {
    k.a = g2l.at(k.a);
    if (!k.is_wall()) k.b = g2l.at(k.b);
  }
  std::vector<Body> bodies;
  for (int g : part.l2g) bodies.push_back(full.bodies()[g]);
  part.sys =
      ContactSystem(std::move(bodies), std::move(contacts), full.rows(), full.params(), owned);
  part.sys.set_rhs(spook_rhs(part.sys));
  return part;
}

void distributed_matches_serial(const ContactSystem &full, Form form)
{
  const int rank = world_rank(), nprocs = world_size();
  const LocalPart part = split(full, rank, nprocs);
  const SlabExchange ex(MPI_COMM_WORLD, full.num_bodies(), part.l2g, part.sys.num_owned_bodies());
  // The local rhs equals the serial one on this rank's contacts.
  Vector b_ref(part.sys.contact_dofs());
  const int rows = full.rows();
  for (std::size_t c = 0; c < part.contact_ids.size(); ++c)
    b_ref.segment(rows * Eigen::Index(c), rows) =
        full.rhs().segment(rows * Eigen::Index(part.contact_ids[c]), rows);
  ASSERT_LT(rel_diff(part.sys.rhs(), b_ref), 1e-14);
  const Vector l = direct_solve(form, part.sys, ex, part.sys.rhs(), MPI_COMM_WORLD);
  const Eigen::VectorXd ref = dense_lambda(full, full.rhs());
  Vector mine(part.sys.contact_dofs());
  for (std::size_t c = 0; c < part.contact_ids.size(); ++c)
    mine.segment(rows * Eigen::Index(c), rows) =
        ref.segment(rows * Eigen::Index(part.contact_ids[c]), rows);
  // Relative to the global norm of lambda: a rank may hold few contacts.
  const double err = ex.sum((l - mine).squaredNorm()), size = ex.sum(mine.squaredNorm());
  EXPECT_LT(std::sqrt(err / size), 1e-8) << "form " << to_string(form);
  // Every rank really had something to do.
  EXPECT_GT(part.sys.num_owned_bodies(), 0);
  EXPECT_GT(part.sys.num_bodies(), part.sys.num_owned_bodies());
}

} // namespace

TEST(DirectMPI, DistributedBodyFormMatchesDense)
{
  if (world_size() < 2) GTEST_SKIP() << "needs mpirun (see LaunchedUnderMpirun)";
  SceneParams p;
  distributed_matches_serial(pile_scene(80, p), Form::body);
  distributed_matches_serial(pile_scene(80, p), Form::contact);
  p.rows = 3;
  distributed_matches_serial(pile_scene(50, p), Form::body);
}

TEST(DirectMPI, DistributedCholeskyRoutesEntries)
{
  if (world_size() < 2) GTEST_SKIP() << "needs mpirun (see LaunchedUnderMpirun)";
  // A 1-D Laplacian plus identity, its entries dealt round-robin, each rank asking for
  // a different, scattered set of solution entries.
  const int rank = world_rank(), nprocs = world_size(), n = 101;
  std::vector<long> r, c, idx;
  std::vector<double> v, val;
  for (int i = 0; i < n; ++i) {
    if (i % nprocs == rank) {
      r.push_back(i), c.push_back(i), v.push_back(3.0);
      if (i + 1 < n) r.push_back(i + 1), c.push_back(i), v.push_back(-1.0);
    }
    if ((i + 1) % nprocs == rank) idx.push_back(i), val.push_back(1.0);
    if (i % 5 == 0) idx.push_back(i), val.push_back(1.0 / nprocs); // summed over ranks
  }
  DistributedCholesky chol(MPI_COMM_WORLD);
  chol.factorize(n, r, c, v);
  std::vector<long> wanted;
  for (int i = n - 1 - rank; i >= 0; i -= 2 + rank) wanted.push_back(i);
  const std::vector<double> x = chol.solve(idx, val, wanted);
  Eigen::MatrixXd S = 3.0 * Eigen::MatrixXd::Identity(n, n);
  for (int i = 0; i + 1 < n; ++i) S(i, i + 1) = S(i + 1, i) = -1.0;
  Eigen::VectorXd rhs = Eigen::VectorXd::Ones(n);
  for (int i = 0; i < n; i += 5) rhs[i] += 1.0;
  const Eigen::VectorXd ref = S.llt().solve(rhs);
  for (std::size_t e = 0; e < wanted.size(); ++e) EXPECT_NEAR(x[e], ref[wanted[e]], 1e-13);
}

TEST(DirectMPI, DistributedLanczosMatchesDense)
{
  // spectra.hpp's Lanczos under MPI (it lives here with the MPI harness): only applies and the
  // operators' global inner products, ghosts kept out of the body-form start vector.
  if (world_size() < 2) GTEST_SKIP() << "needs mpirun (see LaunchedUnderMpirun)";
  SceneParams p;
  const ContactSystem full = pile_scene(12, p);
  const LocalPart part = split(full, world_rank(), world_size());
  const SlabExchange ex(MPI_COMM_WORLD, full.num_bodies(), part.l2g, part.sys.num_owned_bodies());
  const IdentityPreconditioner none;
  for (Form form : {Form::contact, Form::body}) {
    const Spectrum dense = dense_spectrum(*make_operator(form, full, serial_exchange()), none);
    const Spectrum lanczos = lanczos_spectrum(form, part.sys, ex, none);
    EXPECT_NEAR(lanczos.kappa_e, dense.kappa_e, 1e-6 * dense.kappa_e) << to_string(form);
    EXPECT_NEAR(lanczos.lambda_max, dense.lambda_max, 1e-9 * dense.lambda_max);
  }
}

// Runs the MPI cases above under mpirun when this process is alone.
TEST(DirectMPI, LaunchedUnderMpirun)
{
  if (world_size() > 1) GTEST_SKIP() << "already under mpirun";
  char exe[4096];
  const ssize_t len = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
  ASSERT_GT(len, 0);
  exe[len] = '\0';
  // env -i: the child mpirun must not inherit this singleton's Open MPI environment; the
  // sanitizer settings (ctest sets them) are passed on.
  std::string env = "env -i PATH=/usr/bin:/bin HOME=/tmp OMPI_ALLOW_RUN_AS_ROOT=1 "
                    "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1";
  for (const char *name : {"ASAN_OPTIONS", "LSAN_OPTIONS", "UBSAN_OPTIONS"})
    if (const char *value = std::getenv(name)) env += std::string(" ") + name + "='" + value + "'";
  const std::string log = "/tmp/fibre_direct_mpi_" + std::to_string(getpid()) + ".log";
  for (int np : {2, 3}) {
    const std::string cmd = env + " mpirun --oversubscribe -np " + std::to_string(np) + " " + exe +
                            " --gtest_filter='DirectMPI.Distributed*' > " + log + " 2>&1";
    const int status = std::system(cmd.c_str());
    std::string tail;
    if (FILE *f = std::fopen(log.c_str(), "r")) {
      char buf[4096];
      std::size_t got;
      while ((got = std::fread(buf, 1, sizeof(buf), f)) > 0) tail.append(buf, got);
      std::fclose(f);
    }
    if (tail.size() > 4000) tail = tail.substr(tail.size() - 4000);
    EXPECT_EQ(status, 0) << "mpirun -np " << np << " failed:\n" << tail;
    // The distributed tests ran and passed on every rank (gtest prints one line per rank).
    EXPECT_NE(tail.find("[  PASSED  ] 3 tests"), std::string::npos) << tail;
    std::remove(log.c_str());
  }
}
