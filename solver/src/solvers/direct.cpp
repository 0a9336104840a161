#include "fibre/solvers/direct.hpp"

#include <dmumps_c.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <numeric>
#include <string>

#include "fibre/algebra/assembly.hpp"
#include "fibre/algebra/kernels.hpp"
#include "fibre/algebra/operators.hpp"

namespace fibre {

namespace {

// MUMPS documents its parameters 1-based: ICNTL(k) is icntl[k - 1].
constexpr int k(int one_based)
{
  return one_based - 1;
}

std::string infog_meaning(int code)
{
  switch (code) {
  case -1:
    return "error on another process";
  case -2:
    return "number of entries out of range";
  case -3:
    return "invalid JOB (solve before factorization?)";
  case -5:
  case -7:
  case -13:
    return "out of memory";
  case -6:
    return "structurally singular matrix";
  case -8:
  case -9:
  case -14:
  case -15:
    return "internal workspace too small";
  case -10:
    return "numerically singular matrix (not positive definite)";
  case -16:
    return "matrix order out of range";
  case -20:
  case -22:
    return "invalid input array";
  case -21:
    return "invalid PAR for the number of processes";
  default:
    return "see the MUMPS users' guide";
  }
}

// Any rank's failure becomes every rank's, so that nobody enters MUMPS alone.
void collective_check(MPI_Comm comm, bool local_ok, const std::string &what)
{
  int bad = local_ok ? 0 : 1, any = 0;
  MPI_Allreduce(&bad, &any, 1, MPI_INT, MPI_MAX, comm);
  if (any) throw std::invalid_argument("direct solver: " + what);
}

// Indices [begin(r), begin(r + 1)) of a block distribution of n over p ranks.
struct BlockMap {
  long n;
  int p;
  long begin(int r) const { return static_cast<long>((static_cast<long double>(n) * r) / p); }
  int owner(long i) const
  {
    int r = static_cast<int>((static_cast<long double>(i) * p) / n);
    r = std::min(std::max(r, 0), p - 1);
    while (r + 1 < p && begin(r + 1) <= i) ++r;
    while (r > 0 && begin(r) > i) --r;
    return r;
  }
};

struct Entry {
  long index;
  double value;
};

// Sends every item to rank dest[i]; returns what this rank receives, ordered by source rank
// and, within a source, in send order. Collective.
template <class T>
std::vector<T> route(MPI_Comm comm, int nprocs, const std::vector<T> &items,
                     const std::vector<int> &dest, std::vector<int> *recv_counts_out = nullptr)
{
  std::vector<int> send_counts(nprocs, 0), recv_counts(nprocs, 0);
  for (int d : dest) ++send_counts[d];
  MPI_Alltoall(send_counts.data(), 1, MPI_INT, recv_counts.data(), 1, MPI_INT, comm);
  std::vector<int> sdispl(nprocs, 0), rdispl(nprocs, 0);
  for (int r = 1; r < nprocs; ++r) {
    sdispl[r] = sdispl[r - 1] + send_counts[r - 1];
    rdispl[r] = rdispl[r - 1] + recv_counts[r - 1];
  }
  std::vector<T> sorted(items.size());
  std::vector<int> pos = sdispl;
  for (std::size_t i = 0; i < items.size(); ++i) sorted[pos[dest[i]]++] = items[i];
  const int total = rdispl[nprocs - 1] + recv_counts[nprocs - 1];
  std::vector<T> received(total);
  // Bytes keep one code path for every trivially copyable item type.
  auto bytes = [](std::vector<int> v) {
    for (int &x : v) x *= static_cast<int>(sizeof(T));
    return v;
  };
  const auto sc = bytes(send_counts), sd = bytes(sdispl), rc = bytes(recv_counts),
             rd = bytes(rdispl);
  MPI_Alltoallv(sorted.data(), sc.data(), sd.data(), MPI_BYTE, received.data(), rc.data(),
                rd.data(), MPI_BYTE, comm);
  if (recv_counts_out) *recv_counts_out = recv_counts;
  return received;
}

} // namespace

struct DistributedCholesky::Impl {
  MPI_Comm comm = MPI_COMM_NULL;
  int rank = 0, nprocs = 1;
  DMUMPS_STRUC_C id{};
  bool alive = false;
  std::vector<MUMPS_INT> irn, jcn;
  std::vector<double> a;

  void call(int job, const char *stage)
  {
    id.job = job;
    dmumps_c(&id);
    const int info1 = id.infog[k(1)], info2 = id.infog[k(2)];
    if (info1 < 0)
      throw DirectSolverError("MUMPS " + std::string(stage) +
                                  " failed: INFOG(1) = " + std::to_string(info1) + " (" +
                                  infog_meaning(info1) + "), INFOG(2) = " + std::to_string(info2),
                              info1, info2);
  }

  void silence()
  {
    id.icntl[k(1)] = -1; // error messages
    id.icntl[k(2)] = -1; // diagnostics and warnings
    id.icntl[k(3)] = -1; // global information
    id.icntl[k(4)] = 0;  // print level
  }
};

DistributedCholesky::DistributedCholesky(MPI_Comm comm) : impl_(std::make_unique<Impl>())
{
  // A private communicator keeps MUMPS's messages apart from the caller's.
  MPI_Comm_dup(comm, &impl_->comm);
  MPI_Comm_rank(impl_->comm, &impl_->rank);
  MPI_Comm_size(impl_->comm, &impl_->nprocs);
  impl_->id.comm_fortran = static_cast<MUMPS_INT>(MPI_Comm_c2f(impl_->comm));
  impl_->id.par = 1; // the host works too
  impl_->id.sym = 1; // symmetric positive definite: Cholesky without pivoting
  try {
    impl_->call(-1, "initialisation");
  } catch (...) {
    MPI_Comm_free(&impl_->comm);
    throw;
  }
  impl_->alive = true;
  impl_->silence();
}

DistributedCholesky::~DistributedCholesky()
{
  if (impl_->alive) {
    impl_->id.job = -2;
    dmumps_c(&impl_->id);
  }
  MPI_Comm_free(&impl_->comm);
}

void DistributedCholesky::factorize(long n, const std::vector<long> &rows,
                                    const std::vector<long> &cols,
                                    const std::vector<double> &values)
{
  Impl &m = *impl_;
  factorized_ = false;
  collective_check(m.comm, n >= 0 && n < INT_MAX, "matrix order out of range");
  collective_check(m.comm, rows.size() == cols.size() && rows.size() == values.size(),
                   "triplet arrays differ in length");
  bool ok = true;
  for (std::size_t e = 0; e < rows.size() && ok; ++e)
    ok = rows[e] >= 0 && rows[e] < n && cols[e] >= 0 && cols[e] < n && std::isfinite(values[e]);
  collective_check(m.comm, ok, "matrix entry with index out of range or non-finite value");
  n_ = n;
  if (n == 0) {
    factorized_ = true;
    return;
  }
  const std::size_t nz = rows.size();
  m.irn.resize(std::max<std::size_t>(nz, 1));
  m.jcn.resize(std::max<std::size_t>(nz, 1));
  m.a.resize(std::max<std::size_t>(nz, 1));
  for (std::size_t e = 0; e < nz; ++e) {
    // SYM = 1 reads one triangle; MUMPS indices are 1-based.
    const long i = std::min(rows[e], cols[e]), j = std::max(rows[e], cols[e]);
    m.irn[e] = static_cast<MUMPS_INT>(i + 1);
    m.jcn[e] = static_cast<MUMPS_INT>(j + 1);
    m.a[e] = values[e];
  }
  m.silence();
  m.id.n = static_cast<MUMPS_INT>(n);
  m.id.icntl[k(5)] = 0;  // assembled format
  m.id.icntl[k(18)] = 3; // distributed entries, analysis and factorization on each rank's own
  m.id.nnz_loc = static_cast<MUMPS_INT8>(nz);
  m.id.nz_loc = 0;
  m.id.irn_loc = m.irn.data();
  m.id.jcn_loc = m.jcn.data();
  m.id.a_loc = m.a.data();
  m.call(4, "analysis and factorization");
  factorized_ = true;
}

std::vector<double> DistributedCholesky::solve(const std::vector<long> &rhs_index,
                                               const std::vector<double> &rhs_value,
                                               const std::vector<long> &wanted)
{
  Impl &m = *impl_;
  collective_check(m.comm, factorized_, "solve before a successful factorization");
  collective_check(m.comm, rhs_index.size() == rhs_value.size(),
                   "right-hand side arrays differ in length");
  bool ok = true;
  for (std::size_t e = 0; e < rhs_index.size() && ok; ++e)
    ok = rhs_index[e] >= 0 && rhs_index[e] < n_ && std::isfinite(rhs_value[e]);
  for (std::size_t e = 0; e < wanted.size() && ok; ++e) ok = wanted[e] >= 0 && wanted[e] < n_;
  collective_check(m.comm, ok, "right-hand side or requested index out of range");
  if (n_ == 0) return {};

  // 1. Sum the rhs on the block owners: each rank then gives MUMPS a disjoint, complete block.
  const BlockMap map{n_, m.nprocs};
  std::vector<Entry> entries(rhs_index.size());
  std::vector<int> dest(rhs_index.size());
  for (std::size_t e = 0; e < rhs_index.size(); ++e) {
    entries[e] = {rhs_index[e], rhs_value[e]};
    dest[e] = map.owner(rhs_index[e]);
  }
  const long lo = map.begin(m.rank), hi = map.begin(m.rank + 1);
  std::vector<double> block(static_cast<std::size_t>(hi - lo), 0.0);
  for (const Entry &e : route(m.comm, m.nprocs, entries, dest)) block[e.index - lo] += e.value;
  std::vector<MUMPS_INT> irhs(std::max<std::size_t>(block.size(), 1));
  for (long i = lo; i < hi; ++i) irhs[i - lo] = static_cast<MUMPS_INT>(i + 1);
  std::vector<double> rhs_loc(std::max<std::size_t>(block.size(), 1));
  std::copy(block.begin(), block.end(), rhs_loc.begin());

  // 2. Solve with distributed rhs (ICNTL(20) = 10) and solution (ICNTL(21) = 1).
  const int nsol = std::max(m.id.info[k(23)], 0);
  std::vector<double> sol(std::max(nsol, 1));
  std::vector<MUMPS_INT> isol(std::max(nsol, 1));
  m.silence();
  m.id.icntl[k(20)] = 10;
  m.id.icntl[k(21)] = 1;
  m.id.nrhs = 1;
  m.id.nloc_rhs = static_cast<MUMPS_INT>(hi - lo);
  m.id.lrhs_loc = std::max<MUMPS_INT>(m.id.nloc_rhs, 1);
  m.id.irhs_loc = irhs.data();
  m.id.rhs_loc = rhs_loc.data();
  m.id.lsol_loc = std::max(nsol, 1);
  m.id.sol_loc = sol.data();
  m.id.isol_loc = isol.data();
  m.call(3, "solve");

  // 3. Solution pieces to the block owners, then answer every rank's requests from there.
  entries.resize(nsol);
  dest.resize(nsol);
  for (int e = 0; e < nsol; ++e) {
    entries[e] = {static_cast<long>(isol[e]) - 1, sol[e]};
    dest[e] = map.owner(entries[e].index);
  }
  for (const Entry &e : route(m.comm, m.nprocs, entries, dest)) block[e.index - lo] = e.value;
  dest.resize(wanted.size());
  for (std::size_t e = 0; e < wanted.size(); ++e) dest[e] = map.owner(wanted[e]);
  std::vector<int> asked_counts;
  const std::vector<long> asked = route(m.comm, m.nprocs, wanted, dest, &asked_counts);
  // Replies go back to the askers, in the order they asked.
  std::vector<double> replies(asked.size());
  std::vector<int> reply_dest(asked.size());
  std::size_t pos = 0;
  for (int r = 0; r < m.nprocs; ++r)
    for (int c = 0; c < asked_counts[r]; ++c, ++pos) {
      replies[pos] = block[asked[pos] - lo];
      reply_dest[pos] = r;
    }
  const std::vector<double> answers = route(m.comm, m.nprocs, replies, reply_dest);
  // Answers arrive grouped by owner rank, each group in request order: scatter them back.
  std::vector<std::size_t> next(m.nprocs, 0), start(m.nprocs, 0);
  for (std::size_t e = 0; e < wanted.size(); ++e) ++next[dest[e]];
  for (int r = 1; r < m.nprocs; ++r) start[r] = start[r - 1] + next[r - 1];
  std::fill(next.begin(), next.end(), 0);
  std::vector<double> out(wanted.size());
  for (std::size_t e = 0; e < wanted.size(); ++e)
    out[e] = answers[start[dest[e]] + next[dest[e]]++];
  return out;
}

namespace {

Vector solve_contact_form(const ContactSystem &sys, const Exchange &ex, const Vector &b,
                          MPI_Comm comm)
{
  std::vector<long> rows, cols, index(sys.contact_dofs());
  std::vector<double> values;
  upper_triplets(assemble_A(sys, ex.local_owners()), rows, cols, values);
  for (Eigen::Index i = 0; i < sys.contact_dofs(); ++i) index[i] = static_cast<long>(i);
  DistributedCholesky chol(comm);
  chol.factorize(static_cast<long>(sys.contact_dofs()), rows, cols, values);
  const std::vector<double> rhs(b.data(), b.data() + b.size());
  const std::vector<double> x = chol.solve(index, rhs, index);
  return Eigen::Map<const Vector>(x.data(), static_cast<Eigen::Index>(x.size()));
}

Vector solve_body_form(const ContactSystem &sys, const Exchange &ex, const Vector &b, MPI_Comm comm)
{
  long total = 0;
  const std::vector<long> body =
      global_body_index(ex, sys.num_owned_bodies(), sys.num_bodies(), total);
  auto global = [&](Eigen::Index local) {
    return body[local / kBodyDofs] * kBodyDofs + local % kBodyDofs;
  };
  // Local K: this process's contacts on owned and ghost bodies, M on owned bodies. Several
  // local bodies may share one global index (periodic images): keep every local entry whose
  // global position is in the upper triangle, so that MUMPS's sums give the global K.
  const SparseMatrix K = assemble_K(sys);
  std::vector<long> rows, cols;
  std::vector<double> values;
  rows.reserve(K.nonZeros());
  cols.reserve(K.nonZeros());
  values.reserve(K.nonZeros());
  for (Eigen::Index j = 0; j < K.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(K, j); it; ++it) {
      const long gi = global(it.row()), gj = global(it.col());
      if (gi <= gj) {
        rows.push_back(gi);
        cols.push_back(gj);
        values.push_back(it.value());
      }
    }
  DistributedCholesky chol(comm);
  chol.factorize(total * kBodyDofs, rows, cols, values);

  // Local G^T Sigma^-1 b, ghosts included: the solver sums them into their owners.
  Vector g;
  gt_apply(sys, b.cwiseQuotient(sys.sigma()), g);
  std::vector<long> rhs_index(g.size());
  for (Eigen::Index i = 0; i < g.size(); ++i) rhs_index[i] = global(i);
  const std::vector<double> rhs(g.data(), g.data() + g.size());
  const Eigen::Index owned = Eigen::Index(kBodyDofs) * sys.num_owned_bodies();
  std::vector<long> wanted(owned);
  for (Eigen::Index i = 0; i < owned; ++i) wanted[i] = global(i);
  const std::vector<double> x = chol.solve(rhs_index, rhs, wanted);
  Vector dv = Vector::Zero(sys.body_dofs());
  for (Eigen::Index i = 0; i < owned; ++i) dv[i] = x[i];
  return lambda_from_body(sys, ex, b, dv);
}

} // namespace

Vector direct_solve(Form form, const ContactSystem &sys, const Exchange &ex, const Vector &b,
                    MPI_Comm comm)
{
  if (b.size() != sys.contact_dofs())
    throw std::invalid_argument("direct_solve: rhs size " + std::to_string(b.size()) +
                                " differs from the contact rows " +
                                std::to_string(sys.contact_dofs()));
  int nprocs = 1;
  MPI_Comm_size(comm, &nprocs);
  if (form == Form::contact && nprocs == 1) return solve_contact_form(sys, ex, b, comm);
  return solve_body_form(sys, ex, b, comm);
}

Vector refined_body_solution(const ContactSystem &sys, double *refinement)
{
  const Exchange &ex = serial_exchange();
  std::vector<long> rows, cols;
  std::vector<double> values;
  upper_triplets(assemble_K(sys), rows, cols, values);
  DistributedCholesky chol(MPI_COMM_SELF);
  const long n = long(sys.body_dofs());
  chol.factorize(n, rows, cols, values);
  std::vector<long> index(n);
  std::iota(index.begin(), index.end(), 0L);
  auto solve = [&](const Vector &rhs) {
    const std::vector<double> x =
        chol.solve(index, std::vector<double>(rhs.data(), rhs.data() + rhs.size()), index);
    return Vector(Eigen::Map<const Vector>(x.data(), Eigen::Index(x.size())));
  };
  const Vector rhs = body_rhs(sys, ex, sys.rhs());
  Vector dv = solve(rhs);
  const BodySpaceOperator K(sys, ex);
  Vector Kdv;
  K.apply(dv, Kdv);
  const Vector correction = solve(rhs - Kdv);
  dv += correction;
  if (refinement) *refinement = dv.norm() > 0 ? correction.norm() / dv.norm() : 0.0;
  return dv;
}

} // namespace fibre
