#include "fibre/algebra/operators.hpp"

#include "fibre/algebra/spook.hpp"

#include <cmath>

namespace fibre {

double LinearOperator::norm(const Vector &x) const
{
  return std::sqrt(dot(x, x));
}

void ContactSpaceOperator::apply(const Vector &x, Vector &y) const
{
  schur_apply(sys_, ex_, x, y, work_);
}

double ContactSpaceOperator::dot(const Vector &x, const Vector &y) const
{
  return ex_.sum(x.dot(y));
}

void BodySpaceOperator::apply(const Vector &x, Vector &y) const
{
  body_apply(sys_, ex_, x, y, work_);
}

double BodySpaceOperator::dot(const Vector &x, const Vector &y) const
{
  const Eigen::Index owned = Eigen::Index(kBodyDofs) * sys_.num_owned_bodies();
  return ex_.sum(x.head(owned).dot(y.head(owned)));
}

void schur_apply(const ContactSystem &sys, const Exchange &ex, const Vector &x, Vector &y,
                 Vector &work)
{
  gt_apply(sys, x, work);
  ex.reverse_sum(work);
  work.array() *= sys.inv_mass().array();
  ex.forward(work);
  g_sigma_apply(sys, work, x, y);
}

void body_apply(const ContactSystem &sys, const Exchange &ex, const Vector &x, Vector &y,
                Vector &work)
{
  work = x;
  ex.forward(work);
  gt_sigma_inv_g_apply(sys, work, y);
  ex.reverse_sum(y);
  const Eigen::Index owned = Eigen::Index(kBodyDofs) * sys.num_owned_bodies();
  y.head(owned).array() += x.head(owned).array() * sys.mass().head(owned).array();
  y.tail(y.size() - owned).setZero();
}

namespace {
void zero_ghosts(const ContactSystem &sys, Vector &v)
{
  const Eigen::Index owned = Eigen::Index(kBodyDofs) * sys.num_owned_bodies();
  v.tail(v.size() - owned).setZero();
}
} // namespace

Vector body_rhs(const ContactSystem &sys, const Exchange &ex, const Vector &b)
{
  const Vector t = b.cwiseQuotient(sys.sigma());
  Vector y;
  gt_apply(sys, t, y);
  ex.reverse_sum(y);
  zero_ghosts(sys, y);
  return y;
}

Vector lambda_from_body(const ContactSystem &sys, const Exchange &ex, const Vector &b,
                        const Vector &dv)
{
  Vector w = dv;
  ex.forward(w);
  Vector gw;
  g_apply(sys, w, gw);
  return (b - gw).cwiseQuotient(sys.sigma());
}

Vector body_from_lambda(const ContactSystem &sys, const Exchange &ex, const Vector &lambda)
{
  Vector y = velocity_change(sys, ex, lambda);
  zero_ghosts(sys, y);
  return y;
}

std::unique_ptr<LinearOperator> make_operator(Form form, const ContactSystem &sys,
                                              const Exchange &ex)
{
  if (form == Form::contact) return std::make_unique<ContactSpaceOperator>(sys, ex);
  return std::make_unique<BodySpaceOperator>(sys, ex);
}

} // namespace fibre
