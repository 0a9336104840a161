#include "fibre/preconditioners.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>

namespace fibre {

const char *to_string(PrecondKind k)
{
  switch (k) {
    case PrecondKind::none: return "none";
    case PrecondKind::jacobi: return "jacobi";
    case PrecondKind::block: return "block";
    case PrecondKind::fibre: return "fibre";
    case PrecondKind::tree: return "tree";
  }
  return "?";
}

bool parse_precond(const std::string &s, PrecondKind &k)
{
  for (PrecondKind c : {PrecondKind::none, PrecondKind::jacobi, PrecondKind::block,
                        PrecondKind::fibre, PrecondKind::tree})
    if (s == to_string(c)) {
      k = c;
      return true;
    }
  return false;
}

namespace {

#if defined(__clang__)
#define FIBRE_UNROLL _Pragma("unroll")
#elif defined(__GNUC__)
#define FIBRE_UNROLL _Pragma("GCC unroll 6")
#else
#define FIBRE_UNROLL
#endif

using RowMat6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;

constexpr int kB = 6;
constexpr int kBlock = kB * kB;

// ---- 6x6 kernels ----
//
// A Cholesky factor L (column-major, l[i + 6 j]) keeps 1 / L_jj on its diagonal so that the
// solves only multiply. Coupling blocks W are row-major (w[6 i + j]) so that the loops below
// run over contiguous memory.

void cholesky6(double *a)
{
  FIBRE_UNROLL
  for (int j = 0; j < kB; ++j) {
    double d = a[j + kB * j];
    for (int k = 0; k < j; ++k) d -= a[j + kB * k] * a[j + kB * k];
    if (!(d > 0)) throw std::runtime_error("preconditioner block is not positive definite");
    const double inv = 1.0 / std::sqrt(d);
    a[j + kB * j] = inv;
    for (int i = j + 1; i < kB; ++i) {
      double s = a[i + kB * j];
      for (int k = 0; k < j; ++k) s -= a[i + kB * k] * a[j + kB * k];
      a[i + kB * j] = s * inv;
    }
  }
}

// x = L^-1 x.
inline void lower_solve6(const double *l, double *x)
{
  FIBRE_UNROLL
  for (int i = 0; i < kB; ++i) {
    double s = x[i];
    for (int k = 0; k < i; ++k) s -= l[i + kB * k] * x[k];
    x[i] = s * l[i + kB * i];
  }
}

// x = L^-T x.
inline void upper_solve6(const double *l, double *x)
{
  FIBRE_UNROLL
  for (int i = kB - 1; i >= 0; --i) {
    double s = x[i];
    for (int k = i + 1; k < kB; ++k) s -= l[k + kB * i] * x[k];
    x[i] = s * l[i + kB * i];
  }
}

// W = L^-1 W for a row-major W: forward substitution on whole rows.
inline void lower_solve_rows6(const double *l, double *w)
{
  FIBRE_UNROLL
  for (int i = 0; i < kB; ++i) {
    double *wi = w + kB * i;
    for (int k = 0; k < i; ++k) {
      const double lik = l[i + kB * k];
      const double *wk = w + kB * k;
      for (int j = 0; j < kB; ++j) wi[j] -= lik * wk[j];
    }
    const double inv = l[i + kB * i];
    for (int j = 0; j < kB; ++j) wi[j] *= inv;
  }
}

// ---- Block LDL^T of a matrix whose block graph is a forest ----
//
// Nodes are 6x6 blocks, ordered so that every node comes before its parent (leaves first);
// eliminating in that order creates no fill. Node n holds D_n = sign_n L_n L_n^T and the
// block B_n = A(n, parent). A path of nodes is the block Thomas algorithm, isolated nodes
// are the block diagonal. With sign -1 nodes the same code eliminates the augmented
// (quasi-definite) system [-M -G^T; -G Sigma] of a contact tree: there every pivot keeps its
// sign, so no pivoting is needed.
class ForestFactor {
 public:
  ForestFactor(int nodes, int dim)
      : dim_(dim), parent_(nodes, -1), offset_(nodes, -1), sign_(nodes, 1),
        l_(new double[std::size_t(kBlock) * nodes]), w_(new double[std::size_t(kBlock) * nodes])
  {
  }
  int nodes() const { return static_cast<int>(parent_.size()); }
  // Node n: its `dim` entries start at `offset` in the vector (-1: an auxiliary unknown with
  // zero right-hand side whose value is dropped), `parent` > n or -1.
  void set_node(int n, int offset, int parent, int sign)
  {
    offset_[n] = offset;
    parent_[n] = parent;
    sign_[n] = static_cast<signed char>(sign);
  }
  // sign_n D_n before factor() (positive definite; only the lower triangle is read).
  Eigen::Map<Mat6> diag(int n) { return Eigen::Map<Mat6>(l_.get() + std::size_t(kBlock) * n); }
  // B_n = A(n, parent) before factor().
  Eigen::Map<RowMat6> coupling(int n)
  {
    return Eigen::Map<RowMat6>(w_.get() + std::size_t(kBlock) * n);
  }

  void factor()
  {
    for (int n = 0; n < nodes(); ++n) {
      double *l = l_.get() + std::size_t(kBlock) * n;
      cholesky6(l);
      const int p = parent_[n];
      if (p < 0) continue;
      double *w = w_.get() + std::size_t(kBlock) * n;
      lower_solve_rows6(l, w);  // W_n = L_n^-1 B_n
      // D_p -= B_n^T D_n^-1 B_n = sign_n W_n^T W_n, in the parent's signed storage.
      double *dp = l_.get() + std::size_t(kBlock) * p;
      const double s = double(sign_[n] * sign_[p]);
      FIBRE_UNROLL
      for (int b = 0; b < kB; ++b) {
        double *col = dp + kB * b;
        for (int k = 0; k < kB; ++k) {
          const double f = s * w[kB * k + b];
          const double *wk = w + kB * k;
          for (int a = 0; a < kB; ++a) col[a] -= f * wk[a];
        }
      }
    }
  }

  // z = A_forest^-1 r on the nodes' entries; other entries of z are left untouched.
  void solve(const Vector &r, Vector &z, std::vector<double> &work) const
  {
    const int nn = nodes();
    work.resize(std::size_t(kB) * nn);
    double *u = work.data();
    const double *rd = r.data();
    for (int n = 0; n < nn; ++n) {
      double *un = u + kB * n;
      for (int i = 0; i < kB; ++i) un[i] = 0.0;
      if (offset_[n] >= 0)
        for (int i = 0; i < dim_; ++i) un[i] = rd[offset_[n] + i];
    }
    // Forward: u_n = L_n^-1 y_n, then y_p -= sign_n W_n^T u_n.
    for (int n = 0; n < nn; ++n) {
      double *un = u + kB * n;
      lower_solve6(l_.get() + std::size_t(kBlock) * n, un);
      const int p = parent_[n];
      if (p < 0) continue;
      const double *w = w_.get() + std::size_t(kBlock) * n;
      double *up = u + kB * p;
      const double s = sign_[n];
      FIBRE_UNROLL
      for (int k = 0; k < kB; ++k) {
        const double f = s * un[k];
        for (int j = 0; j < kB; ++j) up[j] -= f * w[kB * k + j];
      }
    }
    // Backward, roots first: x_n = sign_n L_n^-T (u_n - W_n x_p), in place of u_n.
    double *zd = z.data();
    for (int n = nn - 1; n >= 0; --n) {
      double *un = u + kB * n;
      const int p = parent_[n];
      if (p >= 0) {
        const double *w = w_.get() + std::size_t(kBlock) * n;
        const double *xp = u + kB * p;
        FIBRE_UNROLL
        for (int k = 0; k < kB; ++k) {
          double t = 0;
          for (int j = 0; j < kB; ++j) t += w[kB * k + j] * xp[j];
          un[k] -= t;
        }
      }
      upper_solve6(l_.get() + std::size_t(kBlock) * n, un);
      if (sign_[n] < 0)
        for (int k = 0; k < kB; ++k) un[k] = -un[k];
      if (offset_[n] >= 0)
        for (int i = 0; i < dim_; ++i) zd[offset_[n] + i] = un[i];
    }
  }

 private:
  int dim_;
  std::vector<int> parent_;
  std::vector<int> offset_;
  std::vector<signed char> sign_;
  std::unique_ptr<double[]> l_;  // 36 per node: D, then its factor
  std::unique_ptr<double[]> w_;  // 36 per node with a parent: B, then W = L^-1 B
};

class ForestPreconditioner final : public Preconditioner {
 public:
  ForestPreconditioner(std::string name, ForestFactor factor, Eigen::Index size,
                       bool covers_all)
      : name_(std::move(name)), factor_(std::move(factor)), size_(size), covers_all_(covers_all)
  {
  }
  // Not reentrant: one preconditioner serves one solve at a time (work_ is shared).
  void apply(const Vector &r, Vector &z) const override
  {
    if (covers_all_) z.resize(size_);
    else z.setZero(size_);
    factor_.solve(r, z, work_);
  }
  std::string name() const override { return name_; }

 private:
  std::string name_;
  ForestFactor factor_;
  Eigen::Index size_;
  bool covers_all_;  // every entry belongs to a node (false: ghost bodies, left zero)
  mutable std::vector<double> work_;
};

// z = D^-1 r with D a positive diagonal (stored inverted).
class DiagonalPreconditioner final : public Preconditioner {
 public:
  explicit DiagonalPreconditioner(Vector inv_diag) : inv_diag_(std::move(inv_diag)) {}
  void apply(const Vector &r, Vector &z) const override { z = inv_diag_.cwiseProduct(r); }
  std::string name() const override { return "jacobi"; }

 private:
  Vector inv_diag_;
};

std::unique_ptr<Preconditioner> finish(const char *name, ForestFactor f, Eigen::Index size,
                                       bool covers_all)
{
  f.factor();
  return std::make_unique<ForestPreconditioner>(name, std::move(f), size, covers_all);
}

// ---- Blocks of A and K in closed form ----
//
// The Jacobian of contact c on its body j (side sign s: + for a, - for b) is
// J = s [D, -Q D; 0, D] with D the frame (rows n, t1, t2) and Q = D [r]x D^T, r = p - x_j:
// Q_ik = r . (d_k x d_i). Then, with mu = 1/m_j and iota = 1/I_j,
//   J M^-1 J'^T = s s' [mu R - iota Q R Q', -iota Q R; iota R Q', iota R],  R = D D'^T,
// which needs 3x3 products only (kernels.cpp forms the 6x6 blocks; this is the fast path).
class BlockBuilder {
 public:
  explicit BlockBuilder(const ContactSystem &sys)
      : sys_(sys), rows_(sys.rows()), masked_(!sys.row_mask().empty())
  {
  }

  Mat3 lever(int c, int side) const
  {
    const ContactKinematics &q = sys_.kinematics(c);
    const Vec3 &r = side == 0 ? q.ra : q.rb;
    const Vec3 d0 = q.frame.row(0), d1 = q.frame.row(1), d2 = q.frame.row(2);
    const double q01 = r.dot(d1.cross(d0)), q02 = r.dot(d2.cross(d0)), q12 = r.dot(d2.cross(d1));
    Mat3 Q;
    Q << 0, q01, q02, -q01, 0, q12, -q02, -q12, 0;
    return Q;
  }
  int body(int c, int side) const
  {
    return side == 0 ? sys_.contacts()[c].a : sys_.contacts()[c].b;
  }
  double mu(int j) const { return sys_.inv_mass()[6 * j]; }
  double iota(int j) const { return sys_.inv_mass()[6 * j + 3]; }

  // Row weights: 1 for active rows, 0 for masked and padding rows.
  Vec6 weights(int c) const
  {
    Vec6 w = Vec6::Zero();
    for (int r = 0; r < rows_; ++r) w[r] = sys_.row_active(Eigen::Index(rows_) * c + r) ? 1 : 0;
    return w;
  }
  // Zero the padding rows/columns (rows() == 3) and the masked ones.
  void restrict(Mat6 &m, int c, int d) const
  {
    if (!masked_ && rows_ == kB) return;
    m = weights(c).asDiagonal() * m * weights(d).asDiagonal();
  }

  // Diagonal block of A (identity on padding rows), as kernels.hpp's diagonal_block.
  Mat6 contact_diag(int c) const
  {
    Mat6 A = Mat6::Zero();
    const int sides = sys_.contacts()[c].is_wall() ? 1 : 2;
    for (int side = 0; side < sides; ++side) {
      const int j = body(c, side);
      const Mat3 Q = lever(c, side);
      const double m = mu(j), i = iota(j);
      A.topLeftCorner<3, 3>() += i * Q * Q.transpose();
      A.topLeftCorner<3, 3>().diagonal().array() += m;
      A.topRightCorner<3, 3>() -= i * Q;
      A.bottomRightCorner<3, 3>().diagonal().array() += i;
    }
    A.bottomLeftCorner<3, 3>() = A.topRightCorner<3, 3>().transpose();
    restrict(A, c, c);
    for (int r = 0; r < kB; ++r)
      A(r, r) += r < rows_ ? sys_.sigma()[Eigen::Index(rows_) * c + r] : 1.0;
    return A;
  }

  // A(c, d) for two contacts sharing bodies (coupling_block of kernels.hpp).
  Mat6 contact_coupling(int c, int d) const
  {
    Mat6 C = Mat6::Zero();
    const Mat3 R = sys_.kinematics(c).frame * sys_.kinematics(d).frame.transpose();
    for (int sc = 0; sc < 2; ++sc)
      for (int sd = 0; sd < 2; ++sd) {
        const int j = body(c, sc);
        if (j < 0 || j != body(d, sd)) continue;
        const Mat3 Qc = lever(c, sc), Qd = lever(d, sd);
        const double s = sc == sd ? 1.0 : -1.0, m = s * mu(j), i = s * iota(j);
        const Mat3 QcR = Qc * R;
        C.topLeftCorner<3, 3>() += m * R - i * QcR * Qd;
        C.topRightCorner<3, 3>() -= i * QcR;
        C.bottomLeftCorner<3, 3>() += i * R * Qd;
        C.bottomRightCorner<3, 3>() += i * R;
      }
    restrict(C, c, d);
    return C;
  }

  // The Jacobian block G_cj (padded and masked rows zero), jacobian_block of kernels.hpp.
  Mat6 jacobian(int c, int side) const
  {
    const Mat3 &D = sys_.kinematics(c).frame;
    const double s = side == 0 ? 1.0 : -1.0;
    Mat6 J;
    J.topLeftCorner<3, 3>() = s * D;
    J.topRightCorner<3, 3>() = -s * lever(c, side) * D;
    J.bottomLeftCorner<3, 3>().setZero();
    J.bottomRightCorner<3, 3>() = s * D;
    if (masked_ || rows_ < kB) J = weights(c).asDiagonal() * J;
    return J;
  }

  // Body-space parts of one contact: J_a^T Sigma^-1 J_a, J_b^T Sigma^-1 J_b and
  // K_ab = J_a^T Sigma^-1 J_b. With F = Q D and S_t, S_r the translational and rotational
  // rows of Sigma^-1 (0 where masked),
  //   J^T Sigma^-1 J' = s s' [D^T S_t D, -D^T S_t F'; -F^T S_t D, F^T S_t F' + D^T S_r D].
  void body_parts(int c, Mat6 &Kaa, Mat6 &Kbb, Mat6 &Kab) const
  {
    const Mat3 &D = sys_.kinematics(c).frame;
    const Vec6 w = weights(c);
    Vec3 st, sr;
    for (int r = 0; r < 3; ++r) {
      st[r] = w[r] / sys_.sigma()[Eigen::Index(rows_) * c + r];
      sr[r] = rows_ == kB ? w[r + 3] / sys_.sigma()[Eigen::Index(rows_) * c + r + 3] : 0.0;
    }
    const Mat3 StD = st.asDiagonal() * D;
    const Mat3 Pt = D.transpose() * StD, Pr = D.transpose() * sr.asDiagonal() * D;
    const Mat3 Fa = lever(c, 0) * D;
    const Mat3 DtStFa = StD.transpose() * Fa;
    Kaa.topLeftCorner<3, 3>() = Pt;
    Kaa.topRightCorner<3, 3>() = -DtStFa;
    Kaa.bottomLeftCorner<3, 3>() = -DtStFa.transpose();
    Kaa.bottomRightCorner<3, 3>() = Fa.transpose() * st.asDiagonal() * Fa + Pr;
    if (sys_.contacts()[c].is_wall()) return;
    const Mat3 Fb = lever(c, 1) * D;
    const Mat3 DtStFb = StD.transpose() * Fb;
    const Mat3 StFb = st.asDiagonal() * Fb;
    Kbb.topLeftCorner<3, 3>() = Pt;
    Kbb.topRightCorner<3, 3>() = -DtStFb;
    Kbb.bottomLeftCorner<3, 3>() = -DtStFb.transpose();
    Kbb.bottomRightCorner<3, 3>() = Fb.transpose() * StFb + Pr;
    Kab.topLeftCorner<3, 3>() = -Pt;
    Kab.topRightCorner<3, 3>() = DtStFb;
    Kab.bottomLeftCorner<3, 3>() = DtStFa.transpose();
    Kab.bottomRightCorner<3, 3>() = -(Fa.transpose() * StFb + Pr);
  }

 private:
  const ContactSystem &sys_;
  int rows_;
  bool masked_;
};

// ---- contact form ----

std::unique_ptr<Preconditioner> contact_jacobi(const ContactSystem &sys)
{
  const BlockBuilder blocks(sys);
  const int rows = sys.rows();
  Vector inv(sys.contact_dofs());
  for (int c = 0; c < sys.num_contacts(); ++c)
    inv.segment(Eigen::Index(rows) * c, rows) =
        blocks.contact_diag(c).diagonal().head(rows).cwiseInverse();
  return std::make_unique<DiagonalPreconditioner>(std::move(inv));
}

std::unique_ptr<Preconditioner> contact_block(const ContactSystem &sys)
{
  const BlockBuilder blocks(sys);
  const int nc = sys.num_contacts(), rows = sys.rows();
  ForestFactor f(nc, rows);
  for (int c = 0; c < nc; ++c) {
    f.set_node(c, rows * c, -1, 1);
    f.diag(c) = blocks.contact_diag(c);
  }
  return finish("block", std::move(f), sys.contact_dofs(), true);
}

// Exact principal submatrix of A on every fibre (block tridiagonal: consecutive contacts
// share one body, others none, and fibres share no body), diagonal blocks elsewhere. Nodes
// follow the fibre numbering: the relabelling happens here, G is never permuted.
std::unique_ptr<Preconditioner> contact_fibre(const ContactSystem &sys, const PrecondOptions &opt,
                                              FibreStats *stats)
{
  const Fibres fib = build_fibres(sys, opt.weight, opt.impulses, true);
  if (stats) *stats = fib.stats;
  const BlockBuilder blocks(sys);
  const int nc = sys.num_contacts(), rows = sys.rows();
  ForestFactor f(nc, rows);
  std::vector<char> in_fibre(nc, 0);
  int n = 0;
  for (int k = 0; k < fib.num_fibres(); ++k) {
    const int first = fib.contact_start[k], last = fib.contact_start[k + 1] - 1;
    for (int i = first; i <= last; ++i, ++n) {
      const int c = fib.contacts[i];
      in_fibre[c] = 1;
      f.set_node(n, rows * c, i < last ? n + 1 : -1, 1);
      f.diag(n) = blocks.contact_diag(c);
      if (i < last) f.coupling(n) = blocks.contact_coupling(c, fib.contacts[i + 1]);
    }
  }
  for (int c = 0; c < nc; ++c)
    if (!in_fibre[c]) {
      f.set_node(n, rows * c, -1, 1);
      f.diag(n++) = blocks.contact_diag(c);
    }
  return finish("fibre", std::move(f), sys.contact_dofs(), true);
}

// Exact principal submatrix of A on the forest's contacts and all wall contacts: the
// augmented system [-M -G^T; -G Sigma] on those contacts and their bodies is a forest
// (bodies and contacts as nodes), eliminated leaves first. Diagonal blocks elsewhere.
std::unique_ptr<Preconditioner> contact_tree(const ContactSystem &sys, const PrecondOptions &opt,
                                             FibreStats *stats)
{
  const Forest forest = build_forest(sys, opt.weight, opt.impulses, true);
  if (stats) *stats = forest.stats;
  const BlockBuilder blocks(sys);
  const int nb = sys.num_bodies(), nc = sys.num_contacts(), rows = sys.rows();
  const std::vector<Contact> &contacts = sys.contacts();

  // Wall contacts per body (CSR) and whether a body has tree children.
  std::vector<int> wall_start(nb + 1, 0), walls;
  for (const Contact &k : contacts)
    if (k.is_wall()) ++wall_start[k.a + 1];
  for (int i = 0; i < nb; ++i) wall_start[i + 1] += wall_start[i];
  walls.resize(wall_start[nb]);
  {
    std::vector<int> fill(wall_start.begin(), wall_start.end() - 1);
    for (int c = 0; c < nc; ++c)
      if (contacts[c].is_wall()) walls[fill[contacts[c].a]++] = c;
  }
  std::vector<char> has_child(nb, 0);
  for (int i = 0; i < nb; ++i)
    if (forest.parent[i] >= 0) has_child[forest.parent[i]] = 1;

  // Leaves first: a body's wall contacts, the body, then the contact to its parent body.
  // Items: contact c -> c (>= 0), body i -> -1 - i.
  std::vector<int> item, body_node(nb, -1);
  std::vector<char> in_tree(nc, 0);
  item.reserve(std::size_t(nc) + nb);
  for (int i : forest.order) {
    if (forest.parent[i] < 0 && !has_child[i] && wall_start[i] == wall_start[i + 1]) continue;
    for (int w = wall_start[i]; w < wall_start[i + 1]; ++w) {
      item.push_back(walls[w]);
      in_tree[walls[w]] = 1;
    }
    body_node[i] = static_cast<int>(item.size());
    item.push_back(-1 - i);
    if (forest.parent_contact[i] >= 0) {
      item.push_back(forest.parent_contact[i]);
      in_tree[forest.parent_contact[i]] = 1;
    }
  }
  for (int c = 0; c < nc; ++c)
    if (!in_tree[c]) item.push_back(c);

  ForestFactor f(static_cast<int>(item.size()), rows);
  const Vector &inv_mass = sys.inv_mass();
  for (int n = 0; n < static_cast<int>(item.size()); ++n) {
    if (item[n] < 0) {  // body i: -M_i, stored as M_i; coupled to its parent contact by -G^T
      const int i = -1 - item[n];
      const int pc = forest.parent_contact[i];
      f.set_node(n, -1, pc >= 0 ? n + 1 : -1, -1);
      f.diag(n) = inv_mass.segment<6>(6 * i).cwiseInverse().asDiagonal();
      if (pc >= 0) f.coupling(n) = -blocks.jacobian(pc, contacts[pc].a == i ? 0 : 1).transpose();
      continue;
    }
    const int c = item[n];
    const Contact &k = contacts[c];
    if (!in_tree[c]) {
      f.set_node(n, rows * c, -1, 1);
      f.diag(n) = blocks.contact_diag(c);
      continue;
    }
    // In the tree: Sigma_c (identity on padding rows), coupled to its parent body by -G_cj.
    const int j = k.is_wall() ? k.a : forest.parent[k.a] == k.b ? k.b : k.a;
    f.set_node(n, rows * c, body_node[j], 1);
    Mat6 d = Mat6::Identity();
    for (int r = 0; r < rows; ++r) d(r, r) = sys.sigma()[Eigen::Index(rows) * c + r];
    f.diag(n) = d;
    f.coupling(n) = -blocks.jacobian(c, j == k.a ? 0 : 1);
  }
  return finish("tree", std::move(f), sys.contact_dofs(), true);
}

// ---- body form ----

// Diagonal blocks of K on owned bodies, complete over processes: ghost copies carry only
// their local contacts' part (not M), which the exchange adds into the owners.
std::vector<Mat6> owned_body_blocks(const ContactSystem &sys, const Exchange &ex)
{
  const int nb = sys.num_bodies(), owned = sys.num_owned_bodies();
  const BlockBuilder blocks(sys);
  std::vector<Mat6> K(nb);
  const Vector &inv_mass = sys.inv_mass();
  for (int i = 0; i < nb; ++i) {
    K[i].setZero();
    if (i < owned) K[i].diagonal() = inv_mass.segment<6>(6 * i).cwiseInverse();
  }
  Mat6 Kaa, Kbb, Kab;
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    blocks.body_parts(c, Kaa, Kbb, Kab);
    K[k.a] += Kaa;
    if (!k.is_wall()) K[k.b] += Kbb;
  }
  Vector col(sys.body_dofs());
  for (int j = 0; j < kB; ++j) {
    for (int i = 0; i < nb; ++i) col.segment<6>(6 * i) = K[i].col(j);
    ex.reverse_sum(col);
    for (int i = 0; i < owned; ++i) K[i].col(j) = col.segment<6>(6 * i);
  }
  K.resize(owned);
  return K;
}

// K(i, j): the sum of J_ci^T Sigma_c^-1 J_cj over the contacts c between bodies i and j.
Mat6 body_pair_block(const ContactSystem &sys, const BlockBuilder &blocks, const ContactGraph &g,
                     int i, int j)
{
  Mat6 sum = Mat6::Zero(), Kaa, Kbb, Kab;
  for (int e = g.start[i]; e < g.start[i + 1]; ++e)
    if (g.neighbour[e] == j) {
      const int c = g.contact[e];
      blocks.body_parts(c, Kaa, Kbb, Kab);
      if (sys.contacts()[c].a == i) sum += Kab;
      else sum += Kab.transpose();
    }
  return sum;
}

std::unique_ptr<Preconditioner> body_jacobi(const ContactSystem &sys, const Exchange &ex)
{
  const std::vector<Mat6> K = owned_body_blocks(sys, ex);
  Vector inv = Vector::Zero(sys.body_dofs());
  for (int i = 0; i < sys.num_owned_bodies(); ++i)
    inv.segment<6>(6 * i) = K[i].diagonal().cwiseInverse();
  return std::make_unique<DiagonalPreconditioner>(std::move(inv));
}

std::unique_ptr<Preconditioner> body_block(const ContactSystem &sys, const Exchange &ex)
{
  const std::vector<Mat6> K = owned_body_blocks(sys, ex);
  const int owned = sys.num_owned_bodies();
  ForestFactor f(owned, kB);
  for (int i = 0; i < owned; ++i) {
    f.set_node(i, 6 * i, -1, 1);
    f.diag(i) = K[i];
  }
  return finish("block", std::move(f), sys.body_dofs(), owned == sys.num_bodies());
}

// Block tridiagonal part of K along every fibre of owned bodies (chain neighbours coupled
// exactly; chords and couplings between fibres dropped), block Thomas; body blocks elsewhere.
std::unique_ptr<Preconditioner> body_fibre(const ContactSystem &sys, const Exchange &ex,
                                           const PrecondOptions &opt, FibreStats *stats)
{
  const Fibres fib = build_fibres(sys, opt.weight, opt.impulses, false);
  if (stats) *stats = fib.stats;
  const ContactGraph g = contact_graph(sys, false);
  const BlockBuilder blocks(sys);
  const std::vector<Mat6> K = owned_body_blocks(sys, ex);
  const int owned = sys.num_owned_bodies();
  ForestFactor f(owned, kB);
  std::vector<char> in_fibre(owned, 0);
  int n = 0;
  for (int k = 0; k < fib.num_fibres(); ++k) {
    const int first = fib.body_start[k], last = fib.body_start[k + 1] - 1;
    for (int p = first; p <= last; ++p, ++n) {
      const int i = fib.bodies[p];
      in_fibre[i] = 1;
      f.set_node(n, 6 * i, p < last ? n + 1 : -1, 1);
      f.diag(n) = K[i];
      if (p < last) f.coupling(n) = body_pair_block(sys, blocks, g, i, fib.bodies[p + 1]);
    }
  }
  for (int i = 0; i < owned; ++i)
    if (!in_fibre[i]) {
      f.set_node(n, 6 * i, -1, 1);
      f.diag(n++) = K[i];
    }
  return finish("fibre", std::move(f), sys.body_dofs(), owned == sys.num_bodies());
}

// K on the forest's edges and all body blocks: tree-structured, Cholesky leaves first.
std::unique_ptr<Preconditioner> body_tree(const ContactSystem &sys, const Exchange &ex,
                                          const PrecondOptions &opt, FibreStats *stats)
{
  const Forest forest = build_forest(sys, opt.weight, opt.impulses, false);
  if (stats) *stats = forest.stats;
  const ContactGraph g = contact_graph(sys, false);
  const BlockBuilder blocks(sys);
  const std::vector<Mat6> K = owned_body_blocks(sys, ex);
  const int owned = sys.num_owned_bodies();
  std::vector<int> node(owned, -1);
  for (int n = 0; n < owned; ++n) node[forest.order[n]] = n;
  ForestFactor f(owned, kB);
  for (int n = 0; n < owned; ++n) {
    const int i = forest.order[n], p = forest.parent[i];
    f.set_node(n, 6 * i, p >= 0 ? node[p] : -1, 1);
    f.diag(n) = K[i];
    if (p >= 0) f.coupling(n) = body_pair_block(sys, blocks, g, i, p);
  }
  return finish("tree", std::move(f), sys.body_dofs(), owned == sys.num_bodies());
}

}  // namespace

std::unique_ptr<Preconditioner> make_preconditioner(Form form, const ContactSystem &sys,
                                                    const Exchange &ex, const PrecondOptions &opt,
                                                    FibreStats *stats)
{
  if (stats) *stats = FibreStats{};
  if (opt.kind == PrecondKind::none) return std::make_unique<IdentityPreconditioner>();
  if (form == Form::contact) {
    switch (opt.kind) {
      case PrecondKind::jacobi: return contact_jacobi(sys);
      case PrecondKind::block: return contact_block(sys);
      case PrecondKind::fibre: return contact_fibre(sys, opt, stats);
      case PrecondKind::tree: return contact_tree(sys, opt, stats);
      case PrecondKind::none: break;
    }
  } else {
    switch (opt.kind) {
      case PrecondKind::jacobi: return body_jacobi(sys, ex);
      case PrecondKind::block: return body_block(sys, ex);
      case PrecondKind::fibre: return body_fibre(sys, ex, opt, stats);
      case PrecondKind::tree: return body_tree(sys, ex, opt, stats);
      case PrecondKind::none: break;
    }
  }
  throw std::invalid_argument("unknown preconditioner");
}

}  // namespace fibre
