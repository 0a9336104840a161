#include "fibre/precond/preconditioner_family.hpp"

#include <cmath>
#include <memory>
#include <stdexcept>

#include "fibre/precond/forest_factor.hpp"

namespace fibre {

namespace {

using namespace forest;

// ---- Blocks of A and K in closed form ----
//
// The Jacobian of contact c on its body j (side sign s: + for a, - for b) is
// J = s [D, -Q D; 0, D] with D the frame (rows d_0 = n, d_1 = t1, d_2 = t2) and
// Q = D [r]x D^T antisymmetric, Q_ik = r . (d_k x d_i), r = p - x_j. With mu = 1/m_j and
// iota = 1/I_j,
//   J M^-1 J'^T = s s' [mu R - iota Q R Q', -iota Q R; iota R Q', iota R],   R = D D'^T,
// so every block is a handful of 3x3 products (kernels.cpp forms the 6x6 products; these are
// the fast paths, checked against the dense reference by the tests).

using M3 = double[3][3];

// The three numbers of an antisymmetric Q: (Q_01, Q_02, Q_12).
struct Skew {
  double a, b, c;
};

// X = Q M.
inline void skew_left(const Skew &q, const M3 &m, M3 &x)
{
  for (int k = 0; k < 3; ++k) {
    x[0][k] = q.a * m[1][k] + q.b * m[2][k];
    x[1][k] = -q.a * m[0][k] + q.c * m[2][k];
    x[2][k] = -q.b * m[0][k] - q.c * m[1][k];
  }
}

// X = M Q.
inline void skew_right(const M3 &m, const Skew &q, M3 &x)
{
  for (int i = 0; i < 3; ++i) {
    x[i][0] = -q.a * m[i][1] - q.b * m[i][2];
    x[i][1] = q.a * m[i][0] - q.c * m[i][2];
    x[i][2] = q.b * m[i][0] + q.c * m[i][1];
  }
}

class BlockBuilder {
 public:
  static constexpr int kPrefetch = 8;

  explicit BlockBuilder(const ContactSystem &sys)
      : sys_(sys), pairs_(sys.body_pairs()), rows_(sys.rows()),
        plain_(sys.row_mask().empty() && sys.rows() == kB)
  {
  }

  void frame(int c, M3 &D) const
  {
    const Mat3 &F = sys_.kinematics(c).frame;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) D[i][k] = F(i, k);
  }
  Skew lever(int c, int side) const
  {
    Skew q[2];
    levers(c, q[0], q[1]);
    return q[side];
  }
  // Both sides at once: the frame's cross products are shared.
  void levers(int c, Skew &qa, Skew &qb) const
  {
    const ContactKinematics &q = sys_.kinematics(c);
    const Vec3 d0 = q.frame.row(0), d1 = q.frame.row(1), d2 = q.frame.row(2);
    const Vec3 x10 = d1.cross(d0), x20 = d2.cross(d0), x21 = d2.cross(d1);
    qa = {q.ra.dot(x10), q.ra.dot(x20), q.ra.dot(x21)};
    qb = {q.rb.dot(x10), q.rb.dot(x20), q.rb.dot(x21)};
  }
  int body(int c, int side) const
  {
    return pairs_[2 * std::size_t(c) + side]; // b = -1 for walls
  }
  // Contact loops run in contact order, but bodies are scattered: ask for the inverse masses
  // of the contact kPrefetch ahead (c may be past the end) and, if given, of another contact.
  void prefetch(int c, int other = -1) const
  {
#if defined(__GNUC__)
    const int ahead = c + kPrefetch;
    if (ahead < sys_.num_contacts()) {
      const int a = pairs_[2 * std::size_t(ahead)], b = pairs_[2 * std::size_t(ahead) + 1];
      __builtin_prefetch(sys_.inv_mass().data() + 6 * a);
      if (b >= 0) __builtin_prefetch(sys_.inv_mass().data() + 6 * b);
    }
    if (other >= 0) {
      __builtin_prefetch(pairs_ + 2 * std::size_t(other));
      __builtin_prefetch(&sys_.kinematics(other));
    }
#else
    (void)c;
    (void)other;
#endif
  }
  double mu(int j) const
  {
    return sys_.inv_mass()[6 * j];
  }
  double iota(int j) const
  {
    return sys_.inv_mass()[6 * j + 3];
  }

  // Row weights: 1 for active rows, 0 for masked and padding rows.
  Vec6 weights(int c) const
  {
    Vec6 w = Vec6::Zero();
    for (int r = 0; r < rows_; ++r) w[r] = sys_.row_active(Eigen::Index(rows_) * c + r) ? 1 : 0;
    return w;
  }

  // Diagonal block of A (identity on padding rows, as kernels.hpp's diagonal_block), its
  // lower triangle packed into l.
  void contact_diag(int c, double *l) const
  {
    // Sums over the sides of mu I + iota Q Q^T (top left), iota Q (bottom left), iota I.
    double t00 = 0, t11 = 0, t22 = 0, t10 = 0, t20 = 0, t21 = 0, qa = 0, qb = 0, qc = 0, ri = 0;
    const int sides = pairs_[2 * std::size_t(c) + 1] < 0 ? 1 : 2;
    Skew lev[2];
    levers(c, lev[0], lev[1]);
    for (int side = 0; side < sides; ++side) {
      const int j = body(c, side);
      const Skew &q = lev[side];
      const double m = mu(j), i = iota(j);
      t00 += m + i * (q.a * q.a + q.b * q.b);
      t11 += m + i * (q.a * q.a + q.c * q.c);
      t22 += m + i * (q.b * q.b + q.c * q.c);
      t10 += i * q.b * q.c;
      t20 -= i * q.a * q.c;
      t21 += i * q.a * q.b;
      qa += i * q.a;
      qb += i * q.b;
      qc += i * q.c;
      ri += i;
    }
    const double packed[kPacked] = {t00, t10, t20, 0, -qa, -qb, t11, t21, qa, 0, -qc,
                                    t22, qb,  qc,  0, ri,  0,   0,   ri,  0,  ri};
    for (int k = 0; k < kPacked; ++k) l[k] = packed[k];
    if (!plain_) {
      const Vec6 w = weights(c);
      for (int j = 0; j < kB; ++j)
        for (int i = j; i < kB; ++i) l[at(i, j)] *= w[i] * w[j];
    }
    for (int r = 0; r < kB; ++r)
      l[at(r, r)] += r < rows_ ? sys_.sigma()[Eigen::Index(rows_) * c + r] : 1.0;
  }
  Vec6 contact_diagonal(int c) const
  {
    double l[kPacked];
    contact_diag(c, l);
    Vec6 d;
    for (int r = 0; r < kB; ++r) d[r] = l[at(r, r)];
    return d;
  }

  // A(c, d) for two contacts sharing bodies (coupling_block of kernels.hpp), row-major into w.
  void contact_coupling(int c, int d, double *w) const
  {
    M3 Dc, Dd, R, QR, RQ, QRQ;
    frame(c, Dc);
    frame(d, Dd);
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k)
        R[i][k] = Dc[i][0] * Dd[k][0] + Dc[i][1] * Dd[k][1] + Dc[i][2] * Dd[k][2];
    bool first = true;
    Skew lc[2], ld[2];
    levers(c, lc[0], lc[1]);
    levers(d, ld[0], ld[1]);
    for (int sc = 0; sc < 2; ++sc)
      for (int sd = 0; sd < 2; ++sd) {
        const int j = body(c, sc);
        if (j < 0 || j != body(d, sd)) continue;
        const Skew &qc = lc[sc], &qd = ld[sd];
        const double s = sc == sd ? 1.0 : -1.0, m = s * mu(j), i = s * iota(j);
        skew_left(qc, R, QR);
        skew_right(R, qd, RQ);
        skew_right(QR, qd, QRQ);
        // w is uninitialised storage: the first shared body writes, a second one adds.
        const bool add = !first;
        first = false;
        for (int r = 0; r < 3; ++r)
          for (int k = 0; k < 3; ++k) {
            double *top = w + kB * r, *bottom = w + kB * (r + 3);
            const double tt = m * R[r][k] - i * QRQ[r][k], tr = -i * QR[r][k];
            const double rt = i * RQ[r][k], rr = i * R[r][k];
            top[k] = add ? top[k] + tt : tt;
            top[k + 3] = add ? top[k + 3] + tr : tr;
            bottom[k] = add ? bottom[k] + rt : rt;
            bottom[k + 3] = add ? bottom[k + 3] + rr : rr;
          }
      }
    if (first)
      for (int k = 0; k < kBlock; ++k) w[k] = 0.0;
    if (!plain_) {
      const Vec6 wc = weights(c), wd = weights(d);
      for (int r = 0; r < kB; ++r)
        for (int k = 0; k < kB; ++k) w[kB * r + k] *= wc[r] * wd[k];
    }
  }

  // The Jacobian block G_cj (padding and masked rows zero), jacobian_block of kernels.hpp.
  Mat6 jacobian(int c, int side) const
  {
    M3 D, QD;
    frame(c, D);
    skew_left(lever(c, side), D, QD);
    const double s = side == 0 ? 1.0 : -1.0;
    Mat6 J;
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) {
        J(r, k) = s * D[r][k];
        J(r, k + 3) = -s * QD[r][k];
        J(r + 3, k) = 0.0;
        J(r + 3, k + 3) = s * D[r][k];
      }
    if (!plain_) J = weights(c).asDiagonal() * J;
    return J;
  }

  // Body-space parts of one contact: J_a^T Sigma^-1 J_a, J_b^T Sigma^-1 J_b and (if
  // `coupling`) K_ab = J_a^T Sigma^-1 J_b. In world axes J = s [D, -D S; 0, D] with
  // S = [r]x; with P_t = D^T S_t D, P_r = D^T S_r D (S_t, S_r the translational and rotational
  // rows of Sigma^-1, 0 where masked or absent) and X = P_t S',
  //   J^T Sigma^-1 J' = s s' [P_t, -X; S P_t, -S X + P_r],   S P_t = -(P_t S)^T.
  void body_parts(int c, Mat6 &Kaa, Mat6 &Kbb, Mat6 *Kab) const
  {
    const Mat3 &D = sys_.kinematics(c).frame;
    double st[3], sr[3];
    const double *sigma = sys_.sigma().data() + std::size_t(rows_) * c;
    const Vec6 w = plain_ ? Vec6::Ones() : weights(c);
    for (int r = 0; r < 3; ++r) {
      st[r] = w[r] / sigma[r];
      sr[r] = rows_ == kB ? w[r + 3] / sigma[r + 3] : 0.0;
    }
    M3 Pt, Pr;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k <= i; ++k) {
        Pt[i][k] = Pt[k][i] =
            st[0] * D(0, i) * D(0, k) + st[1] * D(1, i) * D(1, k) + st[2] * D(2, i) * D(2, k);
        Pr[i][k] = Pr[k][i] =
            sr[0] * D(0, i) * D(0, k) + sr[1] * D(1, i) * D(1, k) + sr[2] * D(2, i) * D(2, k);
      }
    const ContactKinematics &q = sys_.kinematics(c);
    M3 Xa, Xb, SX;
    world_side(Pt, Pr, q.ra, Xa, SX, Kaa);
    if (pairs_[2 * std::size_t(c) + 1] < 0) return;
    world_side(Pt, Pr, q.rb, Xb, SX, Kbb);
    if (!Kab) return;
    // K_ab = -[P_t, -X_b; -X_a^T, -S_a X_b + P_r].
    skew_world_left(q.ra, Xb, SX);
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) {
        (*Kab)(i, k) = -Pt[i][k];
        (*Kab)(i, k + 3) = Xb[i][k];
        (*Kab)(i + 3, k) = Xa[k][i];
        (*Kab)(i + 3, k + 3) = SX[i][k] - Pr[i][k];
      }
  }

 private:
  // X = [r]x M.
  static void skew_world_left(const Vec3 &r, const M3 &m, M3 &x)
  {
    for (int k = 0; k < 3; ++k) {
      x[0][k] = r[1] * m[2][k] - r[2] * m[1][k];
      x[1][k] = r[2] * m[0][k] - r[0] * m[2][k];
      x[2][k] = r[0] * m[1][k] - r[1] * m[0][k];
    }
  }
  // One side's J^T Sigma^-1 J into K, with X = P_t [r]x.
  static void world_side(const M3 &Pt, const M3 &Pr, const Vec3 &r, M3 &X, M3 &SX, Mat6 &K)
  {
    for (int i = 0; i < 3; ++i) { // X = P_t [r]x, row by row
      X[i][0] = Pt[i][1] * r[2] - Pt[i][2] * r[1];
      X[i][1] = Pt[i][2] * r[0] - Pt[i][0] * r[2];
      X[i][2] = Pt[i][0] * r[1] - Pt[i][1] * r[0];
    }
    skew_world_left(r, X, SX);
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) {
        K(i, k) = Pt[i][k];
        K(i, k + 3) = -X[i][k];
        K(i + 3, k) = -X[k][i];
        K(i + 3, k + 3) = Pr[i][k] - SX[i][k];
      }
  }

  const ContactSystem &sys_;
  const int *pairs_; // body pairs, 2 per contact (flat: 8 bytes a contact)
  int rows_;
  bool plain_; // six rows and no mask: the weights are all one
};

// ---- contact form ----
//
// Blocks are computed in contact order (streaming through the system's arrays) and stored at
// their node, which is where the fibre relabelling takes effect.

std::unique_ptr<Preconditioner> contact_jacobi(const ContactSystem &sys)
{
  const BlockBuilder blocks(sys);
  const int rows = sys.rows();
  Vector inv(sys.contact_dofs());
  for (int c = 0; c < sys.num_contacts(); ++c) {
    blocks.prefetch(c);
    inv.segment(Eigen::Index(rows) * c, rows) =
        blocks.contact_diagonal(c).head(rows).cwiseInverse();
  }
  return diagonal(std::move(inv));
}

std::unique_ptr<Preconditioner> contact_block(const ContactSystem &sys)
{
  const BlockBuilder blocks(sys);
  const int nc = sys.num_contacts(), rows = sys.rows();
  ForestFactor f(nc, rows);
  for (int c = 0; c < nc; ++c) f.set_node(c, rows * c, -1, 1);
  f.link();
  for (int c = 0; c < nc; ++c) {
    blocks.prefetch(c);
    blocks.contact_diag(c, f.diag_data(c));
  }
  return finish("block", std::move(f), sys.contact_dofs(), true);
}

// Exact principal submatrix of A on every fibre (block tridiagonal: consecutive contacts
// share one body, others none, and fibres share no body), diagonal blocks elsewhere. Nodes
// follow the fibre numbering: G is never permuted.
std::unique_ptr<Preconditioner> contact_fibre(const ContactSystem &sys, const PrecondOptions &opt,
                                              FibreStats *stats)
{
  const Fibres fib = build_fibres(sys, opt.weight, opt.impulses, true);
  if (stats) *stats = fib.stats;
  const BlockBuilder blocks(sys);
  const int nc = sys.num_contacts(), rows = sys.rows();
  // node[c]: the fibre numbering; next[c]: the following contact of its fibre.
  std::vector<int> node(nc, -1), next(nc, -1);
  int n = 0;
  for (int k = 0; k < fib.num_fibres(); ++k)
    for (int i = fib.contact_start[k]; i < fib.contact_start[k + 1]; ++i) {
      node[fib.contacts[i]] = n++;
      if (i + 1 < fib.contact_start[k + 1]) next[fib.contacts[i]] = fib.contacts[i + 1];
    }
  for (int c = 0; c < nc; ++c)
    if (node[c] < 0) node[c] = n++;
  ForestFactor f(nc, rows);
  for (int c = 0; c < nc; ++c) f.set_node(node[c], rows * c, next[c] >= 0 ? node[c] + 1 : -1, 1);
  f.link();
  for (int c = 0; c < nc; ++c) {
    blocks.prefetch(c, c + 2 < nc ? next[c + 2] : -1);
    blocks.contact_diag(c, f.diag_data(node[c]));
    if (next[c] >= 0) blocks.contact_coupling(c, next[c], f.coupling_data(node[c]));
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
  const int *pairs = sys.body_pairs(); // a, b per contact; b = -1 for walls
  auto body_a = [&](int c) { return pairs[2 * std::size_t(c)]; };
  auto body_b = [&](int c) { return pairs[2 * std::size_t(c) + 1]; };

  // Wall contacts per body (CSR) and whether a body has tree children.
  std::vector<int> wall_start(nb + 1, 0), walls;
  for (int c = 0; c < nc; ++c)
    if (body_b(c) < 0) ++wall_start[body_a(c) + 1];
  for (int i = 0; i < nb; ++i) wall_start[i + 1] += wall_start[i];
  walls.resize(wall_start[nb]);
  {
    std::vector<int> fill(wall_start.begin(), wall_start.end() - 1);
    for (int c = 0; c < nc; ++c)
      if (body_b(c) < 0) walls[fill[body_a(c)]++] = c;
  }
  std::vector<char> has_child(nb, 0);
  for (int i = 0; i < nb; ++i)
    if (forest.parent[i] >= 0) has_child[forest.parent[i]] = 1;

  // Leaves first: a body's wall contacts, the body, then the contact to its parent body.
  std::vector<int> body_node(nb, -1), contact_node(nc, -1);
  int n = 0;
  for (int i : forest.order) {
    if (forest.parent[i] < 0 && !has_child[i] && wall_start[i] == wall_start[i + 1]) continue;
    for (int w = wall_start[i]; w < wall_start[i + 1]; ++w) contact_node[walls[w]] = n++;
    body_node[i] = n++;
    if (forest.parent_contact[i] >= 0) contact_node[forest.parent_contact[i]] = n++;
  }
  const int tree_nodes = n;
  for (int c = 0; c < nc; ++c)
    if (contact_node[c] < 0) contact_node[c] = n++;

  // The tree contact's parent: its wall body, or the end nearer the root.
  auto parent_body = [&](int c) {
    const int a = body_a(c), b = body_b(c);
    return b < 0 ? a : forest.parent[a] == b ? b : a;
  };
  ForestFactor f(n, rows);
  for (int i = 0; i < nb; ++i)
    if (body_node[i] >= 0)
      f.set_node(body_node[i], -1, forest.parent_contact[i] >= 0 ? body_node[i] + 1 : -1, -1);
  for (int c = 0; c < nc; ++c)
    f.set_node(contact_node[c], rows * c,
               contact_node[c] < tree_nodes ? body_node[parent_body(c)] : -1, 1);
  f.link();
  const Vector &inv_mass = sys.inv_mass();
  for (int i = 0; i < nb; ++i) { // body i: -M_i, stored as M_i; -G^T to its parent contact
    if (body_node[i] < 0) continue;
    const int pc = forest.parent_contact[i];
    f.set_diag(body_node[i], Vec6(inv_mass.segment<6>(6 * i).cwiseInverse()));
    if (pc >= 0)
      f.coupling(body_node[i]) = -blocks.jacobian(pc, body_a(pc) == i ? 0 : 1).transpose();
  }
  for (int c = 0; c < nc; ++c) {
    blocks.prefetch(c);
    if (contact_node[c] >= tree_nodes) {
      blocks.contact_diag(c, f.diag_data(contact_node[c]));
      continue;
    }
    // In the tree: Sigma_c (identity on padding rows), coupled to its parent body by -G_cj.
    Vec6 d = Vec6::Ones();
    for (int r = 0; r < rows; ++r) d[r] = sys.sigma()[Eigen::Index(rows) * c + r];
    f.set_diag(contact_node[c], d);
    f.coupling(contact_node[c]) = -blocks.jacobian(c, parent_body(c) == body_a(c) ? 0 : 1);
  }
  return finish("tree", std::move(f), sys.contact_dofs(), true);
}

// ---- body form ----

// The diagonal blocks of K on owned bodies, into the packed diagonal of node[i], complete
// over processes: ghost copies carry only their local contacts' part (not M), which the
// exchange adds into the owners. With `link` (link[i]: the body that owned body i is coupled
// to in the preconditioner, or -1), also K(i, link[i]) into the coupling of node[i], summed
// over parallel contacts. f's topology must be set (link() done).
void body_blocks(const ContactSystem &sys, const Exchange &ex, const std::vector<int> &node,
                 const std::vector<int> *link, ForestFactor &f)
{
  const int nb = sys.num_bodies(), owned = sys.num_owned_bodies();
  const BlockBuilder blocks(sys);
  const Vector &inv_mass = sys.inv_mass();
  for (int i = 0; i < owned; ++i) {
    Vec6 m = inv_mass.segment<6>(6 * i).cwiseInverse();
    f.set_diag(node[i], m);
    if (link && (*link)[i] >= 0) f.coupling(node[i]).setZero();
  }
  std::vector<double> ghost(std::size_t(kPacked) * (nb - owned), 0.0);
  auto packed = [&](int i) {
    return i < owned ? f.diag_data(node[i]) : ghost.data() + std::size_t(kPacked) * (i - owned);
  };
  auto add = [](double *l, const Mat6 &m) {
    for (int j = 0; j < kB; ++j)
      for (int i = j; i < kB; ++i) l[at(i, j)] += m(i, j);
  };
  Mat6 Kaa, Kbb, Kab;
  const int *pairs = sys.body_pairs();
  struct Pair {
    int a, b;
    bool is_wall() const { return b < 0; }
  };
  for (int c = 0; c < sys.num_contacts(); ++c) {
#if defined(__GNUC__)
    if (c + BlockBuilder::kPrefetch < sys.num_contacts()) { // scattered bodies: see prefetch()
      const std::size_t ahead = 2 * std::size_t(c + BlockBuilder::kPrefetch);
      __builtin_prefetch(packed(pairs[ahead]));
      if (pairs[ahead + 1] >= 0) __builtin_prefetch(packed(pairs[ahead + 1]));
    }
#endif
    const Pair k{pairs[2 * std::size_t(c)], pairs[2 * std::size_t(c) + 1]};
    const bool inner = link && !k.is_wall() && k.a < owned && k.b < owned;
    const bool a_to_b = inner && (*link)[k.a] == k.b, b_to_a = inner && (*link)[k.b] == k.a;
    blocks.body_parts(c, Kaa, Kbb, a_to_b || b_to_a ? &Kab : nullptr);
    add(packed(k.a), Kaa);
    if (k.is_wall()) continue;
    add(packed(k.b), Kbb);
    if (a_to_b) f.coupling(node[k.a]) += Kab;
    if (b_to_a) f.coupling(node[k.b]) += Kab.transpose();
  }
  // One collective flag first, so that serial runs and ghost-free decompositions skip the six
  // exchanges (every process takes the same branch).
  if (ex.max(nb > owned ? 1.0 : 0.0) > 0) {
    Vector col(sys.body_dofs());
    for (int j = 0; j < kB; ++j) {
      for (int i = 0; i < nb; ++i)
        for (int r = 0; r < kB; ++r) col[6 * i + r] = packed(i)[r >= j ? at(r, j) : at(j, r)];
      ex.reverse_sum(col);
      for (int i = 0; i < owned; ++i)
        for (int r = j; r < kB; ++r) packed(i)[at(r, j)] = col[6 * i + r];
    }
  }
}

std::unique_ptr<Preconditioner> body_jacobi(const ContactSystem &sys, const Exchange &ex)
{
  const int owned = sys.num_owned_bodies();
  std::vector<int> node(owned);
  ForestFactor f(owned, kB);
  for (int i = 0; i < owned; ++i) f.set_node(node[i] = i, 6 * i, -1, 1);
  f.link();
  body_blocks(sys, ex, node, nullptr, f);
  Vector inv = Vector::Zero(sys.body_dofs());
  for (int i = 0; i < owned; ++i)
    for (int r = 0; r < kB; ++r) inv[6 * i + r] = 1.0 / f.diag_data(i)[at(r, r)];
  return diagonal(std::move(inv));
}

// K's body blocks with K(i, link[i]) for a forest of links over owned bodies; node[i] lists
// children before parents.
std::unique_ptr<Preconditioner> body_forest(const char *name, const ContactSystem &sys,
                                            const Exchange &ex, const std::vector<int> &link,
                                            const std::vector<int> &node)
{
  const int owned = sys.num_owned_bodies();
  ForestFactor f(owned, kB);
  for (int i = 0; i < owned; ++i) f.set_node(node[i], 6 * i, link[i] >= 0 ? node[link[i]] : -1, 1);
  f.link();
  body_blocks(sys, ex, node, &link, f);
  return finish(name, std::move(f), sys.body_dofs(), owned == sys.num_bodies());
}

std::unique_ptr<Preconditioner> body_block(const ContactSystem &sys, const Exchange &ex)
{
  std::vector<int> link(sys.num_owned_bodies(), -1), node(sys.num_owned_bodies());
  for (int i = 0; i < sys.num_owned_bodies(); ++i) node[i] = i;
  return body_forest("block", sys, ex, link, node);
}

// Block tridiagonal part of K along every fibre of owned bodies (chain neighbours coupled
// exactly; chords and couplings between fibres dropped), block Thomas; body blocks elsewhere.
std::unique_ptr<Preconditioner> body_fibre(const ContactSystem &sys, const Exchange &ex,
                                           const PrecondOptions &opt, FibreStats *stats)
{
  const Fibres fib = build_fibres(sys, opt.weight, opt.impulses, false);
  if (stats) *stats = fib.stats;
  const int owned = sys.num_owned_bodies();
  std::vector<int> link(owned, -1), node(owned, -1);
  int n = 0;
  for (int k = 0; k < fib.num_fibres(); ++k)
    for (int p = fib.body_start[k]; p < fib.body_start[k + 1]; ++p) {
      node[fib.bodies[p]] = n++;
      if (p + 1 < fib.body_start[k + 1]) link[fib.bodies[p]] = fib.bodies[p + 1];
    }
  for (int i = 0; i < owned; ++i)
    if (node[i] < 0) node[i] = n++;
  return body_forest("fibre", sys, ex, link, node);
}

// K on the forest's edges and all body blocks: tree-structured, Cholesky leaves first.
std::unique_ptr<Preconditioner> body_tree(const ContactSystem &sys, const Exchange &ex,
                                          const PrecondOptions &opt, FibreStats *stats)
{
  const Forest forest = build_forest(sys, opt.weight, opt.impulses, false);
  if (stats) *stats = forest.stats;
  const int owned = sys.num_owned_bodies();
  std::vector<int> link(forest.parent.begin(), forest.parent.begin() + owned), node(owned, -1);
  for (int n = 0; n < owned; ++n) node[forest.order[n]] = n;
  return body_forest("tree", sys, ex, link, node);
}

} // namespace

std::unique_ptr<Preconditioner> make_preconditioner(Form form, const ContactSystem &sys,
                                                    const Exchange &ex, const PrecondOptions &opt,
                                                    FibreStats *stats)
{
  if (stats) *stats = FibreStats{};
  if (opt.kind == PrecondKind::none) return std::make_unique<IdentityPreconditioner>();
  if (form == Form::contact) {
    switch (opt.kind) {
    case PrecondKind::jacobi:
      return contact_jacobi(sys);
    case PrecondKind::block:
      return contact_block(sys);
    case PrecondKind::fibre:
      return contact_fibre(sys, opt, stats);
    case PrecondKind::tree:
      return contact_tree(sys, opt, stats);
    case PrecondKind::none:
      break;
    }
  } else {
    switch (opt.kind) {
    case PrecondKind::jacobi:
      return body_jacobi(sys, ex);
    case PrecondKind::block:
      return body_block(sys, ex);
    case PrecondKind::fibre:
      return body_fibre(sys, ex, opt, stats);
    case PrecondKind::tree:
      return body_tree(sys, ex, opt, stats);
    case PrecondKind::none:
      break;
    }
  }
  throw std::invalid_argument("unknown preconditioner");
}

} // namespace fibre
