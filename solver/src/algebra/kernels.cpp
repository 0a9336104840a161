#include "fibre/algebra/kernels.hpp"

#include "fibre/algebra/contact_rows.hpp"

namespace fibre {

namespace {

// Rows of contact c that take part (1) or are masked out (0).
inline void row_weights(const ContactSystem &sys, int c, double *wt)
{
  const Eigen::Index base = Eigen::Index(sys.rows()) * c;
  for (int r = 0; r < kMaxRows; ++r)
    wt[r] = (r < sys.rows() && sys.row_active(base + r)) ? 1.0 : 0.0;
}

} // namespace

// ---- The products (the Krylov methods' inner loop) ----
//
// One pass per product over the contacts in contact order, reading per contact its 15
// kinematic numbers (frame D, rows n, t1, t2; levers ra, rb), its two body indices from the
// flat pair array and its 1/Sigma or Sigma rows; the body vectors are gathered and scattered
// by body index. Templated on the row count (3: translational rows only) and on whether rows
// are masked (weights 0/1 multiply the rows), so that the common case carries no branches.
// G_c w = [D (v_a + omega_a x ra - v_b - omega_b x rb) ; D (omega_a - omega_b)];
// G_c^T l: f = D^T l_t, m = D^T l_r; a gets (f, ra x f + m), b gets -(f, rb x f + m).

namespace {

constexpr int kAhead = 16; // prefetch distance in contacts

// The bodies are gathered and scattered by index: ask for those of contact c + kAhead now (the
// contact arrays themselves stream and need no help). rw: 1 when they will be written.
template <int RW> inline void prefetch_bodies(const int *pairs, int c, int nc, const double *v)
{
#if defined(__GNUC__)
  if (c + kAhead >= nc) return;
  const int pa = pairs[2 * std::size_t(c + kAhead)], pb = pairs[2 * std::size_t(c + kAhead) + 1];
  __builtin_prefetch(v + 6 * std::size_t(pa), RW);
  if (pb >= 0) __builtin_prefetch(v + 6 * std::size_t(pb), RW);
#else
  (void)pairs;
  (void)c;
  (void)nc;
  (void)v;
#endif
}

inline const double *kin_data(const ContactSystem &sys)
{
  static_assert(sizeof(ContactKinematics) == 15 * sizeof(double),
                "ContactKinematics must be 15 packed doubles (frame, ra, rb)");
  return sys.num_contacts() > 0 ? sys.kinematics(0).frame.data() : nullptr;
}

// out = G w, plus Sigma x when x is given (the Schur product's diagonal, fused).
template <int R, bool Masked>
void g_kernel(const ContactSystem &sys, const double *w, const double *x, double *out)
{
  const int nc = sys.num_contacts();
  const double *kin = kin_data(sys);
  const int *pairs = sys.body_pairs();
  const double *wt = Masked ? sys.row_weight().data() : nullptr;
  const double *sigma = sys.sigma().data();
  for (int c = 0; c < nc; ++c) {
    prefetch_bodies<0>(pairs, c, nc, w);
    const double *q = kin + 15 * std::size_t(c);
    const int a = pairs[2 * std::size_t(c)], b = pairs[2 * std::size_t(c) + 1];
    double u[6];
    contact_velocity<R>(q, q + 9, q + 12, w + 6 * std::size_t(a),
                        b >= 0 ? w + 6 * std::size_t(b) : nullptr, u);
    double *o = out + std::size_t(R) * c;
    for (int r = 0; r < R; ++r) {
      const std::size_t row = std::size_t(R) * c + r;
      double v = Masked ? wt[row] * u[r] : u[r];
      if (x) v += sigma[row] * x[row];
      o[r] = v;
    }
  }
}

// out += G^T lambda (out zeroed by the caller).
template <int R, bool Masked>
void gt_kernel(const ContactSystem &sys, const double *lambda, double *out)
{
  const int nc = sys.num_contacts();
  const double *kin = kin_data(sys);
  const int *pairs = sys.body_pairs();
  const double *wt = Masked ? sys.row_weight().data() : nullptr;
  for (int c = 0; c < nc; ++c) {
    prefetch_bodies<1>(pairs, c, nc, out);
    const double *q = kin + 15 * std::size_t(c);
    const int a = pairs[2 * std::size_t(c)], b = pairs[2 * std::size_t(c) + 1];
    double l[6] = {0, 0, 0, 0, 0, 0};
    for (int r = 0; r < R; ++r) {
      const std::size_t row = std::size_t(R) * c + r;
      l[r] = Masked ? wt[row] * lambda[row] : lambda[row];
    }
    contact_impulse<R>(q, q + 9, q + 12, l, out + 6 * std::size_t(a),
                       b >= 0 ? out + 6 * std::size_t(b) : nullptr);
  }
}

// out += G^T Sigma^-1 G w in one pass (the body product without its intermediate vector).
template <int R, bool Masked>
FIBRE_INLINE void gtg_kernel(const ContactSystem &sys, const double *w, double *out)
{
  const int nc = sys.num_contacts();
  const double *kin = kin_data(sys);
  const int *pairs = sys.body_pairs();
  const double *wt = Masked ? sys.row_weight().data() : nullptr;
  const double *inv_sigma = sys.inv_sigma().data();
  for (int c = 0; c < nc; ++c) {
    prefetch_bodies<0>(pairs, c, nc, w);
    prefetch_bodies<1>(pairs, c, nc, out);
    const double *q = kin + 15 * std::size_t(c);
    const int a = pairs[2 * std::size_t(c)], b = pairs[2 * std::size_t(c) + 1];
    const double *wb = b >= 0 ? w + 6 * std::size_t(b) : nullptr;
    double u[6] = {0, 0, 0, 0, 0, 0};
    contact_velocity<R>(q, q + 9, q + 12, w + 6 * std::size_t(a), wb, u);
    for (int r = 0; r < R; ++r) {
      const std::size_t row = std::size_t(R) * c + r;
      u[r] *= Masked ? wt[row] * inv_sigma[row] : inv_sigma[row]; // weights are 0 or 1
    }
    contact_impulse<R>(q, q + 9, q + 12, u, out + 6 * std::size_t(a),
                       b >= 0 ? out + 6 * std::size_t(b) : nullptr);
  }
}

template <template <int, bool> class F, typename... Args>
void dispatch(const ContactSystem &sys, Args... args)
{
  const bool masked = sys.row_weight().size() > 0;
  if (sys.rows() == 6) {
    if (masked)
      F<6, true>::run(sys, args...);
    else
      F<6, false>::run(sys, args...);
  } else {
    if (masked)
      F<3, true>::run(sys, args...);
    else
      F<3, false>::run(sys, args...);
  }
}

template <int R, bool M> struct GRun {
  static void run(const ContactSystem &s, const double *w, const double *x, double *o)
  {
    g_kernel<R, M>(s, w, x, o);
  }
};
template <int R, bool M> struct GtRun {
  static void run(const ContactSystem &s, const double *l, double *o) { gt_kernel<R, M>(s, l, o); }
};
template <int R, bool M> struct GtgRun {
  static void run(const ContactSystem &s, const double *w, double *o) { gtg_kernel<R, M>(s, w, o); }
};

} // namespace

void g_apply(const ContactSystem &sys, const Vector &w, Vector &out)
{
  out.resize(sys.contact_dofs());
  dispatch<GRun>(sys, w.data(), static_cast<const double *>(nullptr), out.data());
}

void gt_apply(const ContactSystem &sys, const Vector &lambda, Vector &out)
{
  out.setZero(sys.body_dofs());
  dispatch<GtRun>(sys, lambda.data(), out.data());
}

void g_sigma_apply(const ContactSystem &sys, const Vector &w, const Vector &x, Vector &out)
{
  out.resize(sys.contact_dofs());
  dispatch<GRun>(sys, w.data(), x.data(), out.data());
}

void gt_sigma_inv_g_apply(const ContactSystem &sys, const Vector &w, Vector &out)
{
  out.setZero(sys.body_dofs());
  dispatch<GtgRun>(sys, w.data(), out.data());
}

Mat6 jacobian_block(const ContactSystem &sys, int c, int side)
{
  const Contact &k = sys.contacts()[c];
  const ContactKinematics &q = sys.kinematics(c);
  Mat6 J = Mat6::Zero();
  if (side == 1 && k.is_wall()) return J;
  const double sign = side == 0 ? 1.0 : -1.0;
  const Vec3 &r = side == 0 ? q.ra : q.rb;
  for (int i = 0; i < 3; ++i) {
    const Vec3 d = q.frame.row(i).transpose();
    J.block<1, 3>(i, 0) = sign * d.transpose();
    J.block<1, 3>(i, 3) = sign * r.cross(d).transpose();
    J.block<1, 3>(i + 3, 3) = sign * d.transpose();
  }
  double wt[kMaxRows];
  row_weights(sys, c, wt);
  for (int r = 0; r < kMaxRows; ++r) J.row(r) *= wt[r];
  return J;
}

namespace {
inline Eigen::Matrix<double, 6, 1> body_inv_mass(const ContactSystem &sys, int body)
{
  return sys.inv_mass().segment<6>(6 * body);
}
} // namespace

Mat6 diagonal_block(const ContactSystem &sys, int c)
{
  const Contact &k = sys.contacts()[c];
  const Mat6 Ja = jacobian_block(sys, c, 0);
  Mat6 D = Ja * body_inv_mass(sys, k.a).asDiagonal() * Ja.transpose();
  if (!k.is_wall()) {
    const Mat6 Jb = jacobian_block(sys, c, 1);
    D += Jb * body_inv_mass(sys, k.b).asDiagonal() * Jb.transpose();
  }
  const int rows = sys.rows();
  for (int r = 0; r < kMaxRows; ++r) {
    if (r < rows) {
      D(r, r) += sys.sigma()[Eigen::Index(rows) * c + r];
    } else {
      D.row(r).setZero();
      D.col(r).setZero();
      D(r, r) = 1.0;
    }
  }
  return D;
}

Vec6 diagonal_entries(const ContactSystem &sys, int c, double split_a, double split_b)
{
  const int rows = sys.rows();
  double wt[kMaxRows];
  row_weights(sys, c, wt);
  const std::array<Vec6, 2> &sides = sys.diagonal_sides(c);
  Vec6 d = Vec6::Ones();
  for (int r = 0; r < rows; ++r)
    d[r] = sys.sigma()[Eigen::Index(rows) * c + r] + split_a * wt[r] * sides[0][r];
  if (sys.body_pairs()[2 * std::size_t(c) + 1] >= 0) // a pair, not a wall
    for (int r = 0; r < rows; ++r) d[r] += split_b * wt[r] * sides[1][r];
  return d;
}

Mat6 coupling_block(const ContactSystem &sys, int c, int d)
{
  const Contact &kc = sys.contacts()[c], &kd = sys.contacts()[d];
  Mat6 C = Mat6::Zero();
  const int bc[2] = {kc.a, kc.b}, bd[2] = {kd.a, kd.b};
  for (int sc = 0; sc < 2; ++sc)
    for (int sd = 0; sd < 2; ++sd)
      if (bc[sc] >= 0 && bc[sc] == bd[sd])
        C += jacobian_block(sys, c, sc) * body_inv_mass(sys, bc[sc]).asDiagonal() *
             jacobian_block(sys, d, sd).transpose();
  return C;
}

namespace {
inline Eigen::Matrix<double, 6, 1> inv_sigma_rows(const ContactSystem &sys, int c)
{
  Eigen::Matrix<double, 6, 1> s = Eigen::Matrix<double, 6, 1>::Zero();
  for (int r = 0; r < sys.rows(); ++r) s[r] = 1.0 / sys.sigma()[Eigen::Index(sys.rows()) * c + r];
  return s;
}
} // namespace

std::vector<Mat6> body_diagonal_blocks(const ContactSystem &sys)
{
  std::vector<Mat6> K(sys.num_bodies());
  for (int i = 0; i < sys.num_bodies(); ++i)
    K[i] = body_inv_mass(sys, i).cwiseInverse().asDiagonal();
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    const auto s = inv_sigma_rows(sys, c);
    const Mat6 Ja = jacobian_block(sys, c, 0);
    K[k.a] += Ja.transpose() * s.asDiagonal() * Ja;
    if (!k.is_wall()) {
      const Mat6 Jb = jacobian_block(sys, c, 1);
      K[k.b] += Jb.transpose() * s.asDiagonal() * Jb;
    }
  }
  return K;
}

Mat6 body_coupling_block(const ContactSystem &sys, int c)
{
  if (sys.contacts()[c].is_wall()) return Mat6::Zero();
  return jacobian_block(sys, c, 0).transpose() * inv_sigma_rows(sys, c).asDiagonal() *
         jacobian_block(sys, c, 1);
}

} // namespace fibre
