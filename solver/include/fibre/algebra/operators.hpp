// The two forms of the regularized contact system (thesis 2.2, doc/design.md section 7) as
// linear operators that the Krylov methods and preconditioners see.
#pragma once

#include <memory>
#include <string>

#include "fibre/algebra/kernels.hpp"
#include "fibre/core/exchange.hpp"
#include "fibre/core/names.hpp"

namespace fibre {

enum class Form { contact, body };
template <> struct EnumNames<Form> {
  static constexpr EnumName<Form> table[] = {{Form::body, "body"}, {Form::contact, "contact"}};
};

// Symmetric positive definite operator with its own (global) inner product.
class LinearOperator {
 public:
  virtual ~LinearOperator() = default;
  virtual Eigen::Index size() const = 0;
  virtual void apply(const Vector &x, Vector &y) const = 0;
  virtual double dot(const Vector &x, const Vector &y) const = 0;
  double norm(const Vector &x) const;
};

// Contact space (dual): A lambda = b, A = G M^-1 G^T + Sigma. Every contact is owned by
// exactly one process, so dot = local dot + global sum.
class ContactSpaceOperator final : public LinearOperator {
 public:
  ContactSpaceOperator(const ContactSystem &sys, const Exchange &ex) : sys_(sys), ex_(ex) {}
  Eigen::Index size() const override { return sys_.contact_dofs(); }
  void apply(const Vector &x, Vector &y) const override;
  double dot(const Vector &x, const Vector &y) const override;

 private:
  const ContactSystem &sys_;
  const Exchange &ex_;
  mutable Vector work_;
};

// Body space (primal): K dv = G^T Sigma^-1 b, K = M + G^T Sigma^-1 G. Vectors cover owned
// and ghost bodies; only owned entries are meaningful, dot sums owned entries.
class BodySpaceOperator final : public LinearOperator {
 public:
  BodySpaceOperator(const ContactSystem &sys, const Exchange &ex) : sys_(sys), ex_(ex) {}
  Eigen::Index size() const override { return sys_.body_dofs(); }
  void apply(const Vector &x, Vector &y) const override;
  double dot(const Vector &x, const Vector &y) const override;

 private:
  const ContactSystem &sys_;
  const Exchange &ex_;
  mutable Vector work_;
};

// y = (G M^-1 G^T + Sigma) x. `work` is a body-space scratch vector.
void schur_apply(const ContactSystem &sys, const Exchange &ex, const Vector &x, Vector &y,
                 Vector &work);
// y = (M + G^T Sigma^-1 G) x for a body-space x; ghost entries of y are zero.
void body_apply(const ContactSystem &sys, const Exchange &ex, const Vector &x, Vector &y,
                Vector &work);

// Body-space right-hand side G^T Sigma^-1 b (owned entries complete, ghosts zero).
Vector body_rhs(const ContactSystem &sys, const Exchange &ex, const Vector &b);
// lambda = Sigma^-1 (b - G dv) from a body-space solution dv (owned entries).
Vector lambda_from_body(const ContactSystem &sys, const Exchange &ex, const Vector &b,
                        const Vector &dv);
// Body-space initial guess from a contact-space one: dv = M^-1 G^T lambda (owned entries).
Vector body_from_lambda(const ContactSystem &sys, const Exchange &ex, const Vector &lambda);

std::unique_ptr<LinearOperator> make_operator(Form form, const ContactSystem &sys,
                                              const Exchange &ex);

} // namespace fibre
