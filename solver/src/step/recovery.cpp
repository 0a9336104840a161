#include "fibre/step/recovery.hpp"

#include <algorithm>

#include "fibre/algebra/cones.hpp"
#include "fibre/algebra/kernels.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/solvers/pgs.hpp"

namespace fibre {

namespace {

// Whether the split recovery opens contact c: a rigid row's penetration.
bool recovered(const Contact &c)
{
  return c.penetration > 0 && !c.elastic[0];
}

// The target opening speed of each normal row: a penetration's overlap left after the step, at
// most max_recovery; an open contact may close by its gap; a touching one not further.
Vector recovery_rhs(const ContactSystem &sys, const Vector &v_plus)
{
  const SpookParams &p = sys.params();
  const int rows = sys.rows();
  Vector Gv;
  g_apply(sys, v_plus, Gv);
  Vector b = Vector::Zero(sys.contact_dofs());
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    const Eigen::Index row = Eigen::Index(rows) * c;
    const double gap = gap_after(k, p.h, Gv[row], sys.walls_move());
    if (recovered(k))
      b[row] = std::min(std::max(-gap, 0.0) / p.h, p.max_recovery);
    else
      b[row] = std::min(-gap / p.h, 0.0);
  }
  return b;
}

} // namespace

bool has_rigid_penetration(const ContactSystem &sys, const Exchange &ex)
{
  double any = std::any_of(sys.contacts().begin(), sys.contacts().end(), recovered);
  ex.max(&any, 1);
  return any > 0;
}

bool recovery_displacement(const ContactSystem &sys, const Exchange &ex, const Vector &v_plus,
                           Vector &dx, int max_sweeps)
{
  if (!has_rigid_penetration(sys, ex)) return false;
  const Cones frictionless = Cones::frictionless(sys);
  const Vector b = recovery_rhs(sys, v_plus);
  Vector mu = Vector::Zero(sys.contact_dofs());
  PgsControl control;
  control.max_sweeps = max_sweeps;
  control.tol = 1e-3;
  pgs(sys, ex, frictionless, b, row_scales(sys), mu, control);
  dx = velocity_change(sys, ex, mu);
  const double h = sys.params().h, reach = h * sys.params().max_recovery;
  double fastest = 0.0;
  for (int i = 0; i < sys.num_bodies(); ++i) {
    Eigen::Ref<Vector> body = dx.segment(6 * Eigen::Index(i), 6);
    body.tail<3>().setZero();
    fastest = std::max(fastest, h * body.head<3>().norm());
  }
  ex.max(&fastest, 1);
  dx *= fastest > reach ? h * reach / fastest : h;
  return true;
}

} // namespace fibre
