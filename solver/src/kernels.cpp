#include "fibre/kernels.hpp"

namespace fibre {

namespace {

// Rows of contact c that take part (1) or are masked out (0).
inline void row_weights(const ContactSystem &sys, int c, double *wt)
{
  const Eigen::Index base = Eigen::Index(sys.rows()) * c;
  for (int r = 0; r < kMaxRows; ++r)
    wt[r] = (r < sys.rows() && sys.row_active(base + r)) ? 1.0 : 0.0;
}

// Contact-frame velocity of one side: [D (v + omega x r) ; D omega].
inline Vec6 side_velocity(const Mat3 &D, const Vec3 &r, const double *w)
{
  const Eigen::Map<const Vec3> v(w), omega(w + 3);
  Vec6 u;
  u.head<3>() = D * (v + omega.cross(r));
  u.tail<3>() = D * omega;
  return u;
}

// Generalized force of an impulse l (contact frame) on one side: [f ; r x f + D^T l_rot].
inline void add_side_impulse(const Mat3 &D, const Vec3 &r, const Vec6 &l, double sign, double *out)
{
  const Vec3 f = sign * (D.transpose() * l.head<3>());
  const Vec3 tau = r.cross(f) + sign * (D.transpose() * l.tail<3>());
  Eigen::Map<Vec3>(out) += f;
  Eigen::Map<Vec3>(out + 3) += tau;
}

}  // namespace

void g_apply(const ContactSystem &sys, const Vector &w, Vector &out)
{
  const int rows = sys.rows(), nc = sys.num_contacts();
  out.resize(sys.contact_dofs());
  double wt[kMaxRows];
  for (int c = 0; c < nc; ++c) {
    const Contact &k = sys.contacts()[c];
    const ContactKinematics &q = sys.kinematics(c);
    Vec6 u = side_velocity(q.frame, q.ra, w.data() + 6 * k.a);
    if (!k.is_wall()) u -= side_velocity(q.frame, q.rb, w.data() + 6 * k.b);
    row_weights(sys, c, wt);
    for (int r = 0; r < rows; ++r) out[Eigen::Index(rows) * c + r] = wt[r] * u[r];
  }
}

void gt_apply(const ContactSystem &sys, const Vector &lambda, Vector &out)
{
  const int rows = sys.rows(), nc = sys.num_contacts();
  out.setZero(sys.body_dofs());
  double wt[kMaxRows];
  for (int c = 0; c < nc; ++c) {
    const Contact &k = sys.contacts()[c];
    const ContactKinematics &q = sys.kinematics(c);
    row_weights(sys, c, wt);
    Vec6 l = Vec6::Zero();
    for (int r = 0; r < rows; ++r) l[r] = wt[r] * lambda[Eigen::Index(rows) * c + r];
    add_side_impulse(q.frame, q.ra, l, 1.0, out.data() + 6 * k.a);
    if (!k.is_wall()) add_side_impulse(q.frame, q.rb, l, -1.0, out.data() + 6 * k.b);
  }
}

void schur_apply(const ContactSystem &sys, const Exchange &ex, const Vector &x, Vector &y,
                 Vector &work)
{
  gt_apply(sys, x, work);
  ex.reverse_sum(work);
  work.array() *= sys.inv_mass().array();
  ex.forward(work);
  g_apply(sys, work, y);
  y.array() += sys.sigma().array() * x.array();
}

void body_apply(const ContactSystem &sys, const Exchange &ex, const Vector &x, Vector &y,
                Vector &work)
{
  work = x;
  ex.forward(work);
  Vector t;
  g_apply(sys, work, t);
  t.array() /= sys.sigma().array();
  gt_apply(sys, t, y);
  ex.reverse_sum(y);
  const Eigen::Index owned = Eigen::Index(kBodyDofs) * sys.num_owned_bodies();
  y.head(owned).array() += x.head(owned).array() / sys.inv_mass().head(owned).array();
  y.tail(y.size() - owned).setZero();
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
}  // namespace

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
}  // namespace

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

Vector mass_diagonal(const ContactSystem &sys)
{
  return sys.inv_mass().cwiseInverse();
}

}  // namespace fibre
