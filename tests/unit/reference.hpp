// Independent dense references for the unit tests: G, M^-1 and A assembled entry by entry
// from the thesis's block formula (eq. 2.1.1), without the library's kernels.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <utility>

#include "fibre/core/system.hpp"

namespace fibre::test {

using Dense = Eigen::MatrixXd;

// ||a - b|| / ||b|| (Frobenius for matrices), safe for b = 0.
template <typename A, typename B>
double rel_diff(const Eigen::MatrixBase<A> &a, const Eigen::MatrixBase<B> &b)
{
  return (a - b).norm() / std::max(b.norm(), 1e-300);
}

// Dense G: rows() per contact, 6 per body (masked rows zero).
inline Dense dense_G(const ContactSystem &sys)
{
  const int rows = sys.rows();
  Dense G = Dense::Zero(sys.contact_dofs(), sys.body_dofs());
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    const Vec3 dirs[3] = {k.normal, k.t1, k.t2};
    for (int r = 0; r < rows; ++r) {
      const Eigen::Index row = Eigen::Index(rows) * c + r;
      if (!sys.row_active(row)) continue;
      const Vec3 &d = dirs[r % 3];
      if (r < 3) {
        G.block<1, 3>(row, 6 * k.a) = d.transpose();
        G.block<1, 3>(row, 6 * k.a + 3) = (k.point - sys.bodies()[k.a].x).cross(d).transpose();
        if (!k.is_wall()) {
          G.block<1, 3>(row, 6 * k.b) = -d.transpose();
          G.block<1, 3>(row, 6 * k.b + 3) = -(k.point - sys.bodies()[k.b].x).cross(d).transpose();
        }
      } else {
        G.block<1, 3>(row, 6 * k.a + 3) = d.transpose();
        if (!k.is_wall()) G.block<1, 3>(row, 6 * k.b + 3) = -d.transpose();
      }
    }
  }
  return G;
}

inline Dense dense_Minv(const ContactSystem &sys)
{
  Dense Minv = Dense::Zero(sys.body_dofs(), sys.body_dofs());
  for (int i = 0; i < sys.num_bodies(); ++i) {
    const Body &b = sys.bodies()[i];
    for (int k = 0; k < 3; ++k) {
      Minv(6 * i + k, 6 * i + k) = 1.0 / b.mass;
      Minv(6 * i + 3 + k, 6 * i + 3 + k) = 1.0 / (0.4 * b.mass * b.radius * b.radius);
    }
  }
  return Minv;
}

inline Eigen::VectorXd dense_sigma(const ContactSystem &sys)
{
  Eigen::VectorXd s(sys.contact_dofs());
  const SpookParams &p = sys.params();
  for (int c = 0; c < sys.num_contacts(); ++c)
    for (int r = 0; r < sys.rows(); ++r) {
      const Contact &k = sys.contacts()[c];
      // the row's own damping, else the contact's, else the system's
      const double d = r > 0 && k.spring_damping[r] >= 0 ? k.spring_damping[r]
                       : k.damping >= 0                  ? k.damping
                                                         : p.damping;
      const Eigen::Index row = Eigen::Index(sys.rows()) * c + r;
      s[row] = sys.row_active(row) ? 4.0 * k.compliance[r] / (p.h * p.h * (1.0 + 4.0 * d)) : 1.0;
    }
  return s;
}

// A = G M^-1 G^T + Sigma.
inline Dense dense_A(const ContactSystem &sys)
{
  const Dense G = dense_G(sys);
  Dense A = G * dense_Minv(sys) * G.transpose();
  A.diagonal() += dense_sigma(sys);
  return A;
}

// K = M + G^T Sigma^-1 G.
inline Dense dense_K(const ContactSystem &sys)
{
  const Dense G = dense_G(sys);
  Dense K = G.transpose() * dense_sigma(sys).cwiseInverse().asDiagonal() * G;
  K.diagonal() += dense_Minv(sys).diagonal().cwiseInverse();
  return K;
}

// One classical Runge-Kutta step of d'' = accel(d, d') from (d, u): the next (d, u). The tests'
// reference for a contact law's collision, apart from the library's own integration.
template <typename Accel>
std::pair<double, double> rk4_step(double d, double u, double dt, const Accel &accel)
{
  const double k1d = u, k1u = accel(d, u);
  const double k2d = u + 0.5 * dt * k1u, k2u = accel(d + 0.5 * dt * k1d, k2d);
  const double k3d = u + 0.5 * dt * k2u, k3u = accel(d + 0.5 * dt * k2d, k3d);
  const double k4d = u + dt * k3u, k4u = accel(d + dt * k3d, k4d);
  return {d + dt / 6.0 * (k1d + 2.0 * k2d + 2.0 * k3d + k4d),
          u + dt / 6.0 * (k1u + 2.0 * k2u + 2.0 * k3u + k4u)};
}

} // namespace fibre::test
