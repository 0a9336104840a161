#include "fibre/spook.hpp"

#include "fibre/kernels.hpp"

namespace fibre {

Vector body_velocities(const ContactSystem &sys)
{
  Vector v(sys.body_dofs());
  for (int i = 0; i < sys.num_bodies(); ++i) {
    v.segment<3>(6 * i) = sys.bodies()[i].v;
    v.segment<3>(6 * i + 3) = sys.bodies()[i].omega;
  }
  return v;
}

Vector external_velocity_change(const ContactSystem &sys)
{
  Vector dv(sys.body_dofs());
  const double h = sys.params().h;
  for (int i = 0; i < sys.num_bodies(); ++i) {
    dv.segment<3>(6 * i) = h * sys.bodies()[i].force;
    dv.segment<3>(6 * i + 3) = h * sys.bodies()[i].torque;
  }
  return dv.cwiseProduct(sys.inv_mass());
}

Vector spook_rhs(const ContactSystem &sys, const Vector *extra_dv)
{
  const SpookParams &p = sys.params();
  const double ups = p.upsilon();
  Vector w = (1.0 - ups) * body_velocities(sys) + external_velocity_change(sys);
  if (extra_dv) w += *extra_dv;
  Vector b;
  g_apply(sys, w, b);
  b = -b;
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Eigen::Index row = Eigen::Index(sys.rows()) * c; // normal row
    if (sys.row_active(row)) b[row] += p.gap_term(sys.contacts()[c].gap);
  }
  return b;
}

Vector velocity_change(const ContactSystem &sys, const Exchange &ex, const Vector &lambda)
{
  Vector dv;
  gt_apply(sys, lambda, dv);
  ex.reverse_sum(dv);
  dv.array() *= sys.inv_mass().array();
  ex.forward(dv);
  return dv;
}

} // namespace fibre
