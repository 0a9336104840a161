// Two preconditioners of the family combined into one (multipreconditioning): the average of
// their inverses and a symmetric multiplicative sweep (fibre_analyze --combine).
#pragma once

#include <memory>
#include <string>

#include "fibre/algebra/operators.hpp"
#include "fibre/precond/preconditioner.hpp"

namespace fibre {

// P^-1 = (P1^-1 + P2^-1) / 2: symmetric positive definite when both are.
class AveragePreconditioner final : public Preconditioner {
 public:
  AveragePreconditioner(std::unique_ptr<Preconditioner> first,
                        std::unique_ptr<Preconditioner> second, std::string name);
  void apply(const Vector &r, Vector &z) const override;
  std::string name() const override { return name_; }

 private:
  std::unique_ptr<Preconditioner> first_, second_;
  std::string name_;
  mutable Vector tmp_;
};

// Symmetric multiplicative combination (outer O, inner I), a symmetric Gauss-Seidel sweep over
// the two preconditioners:
//   z = O r; z += I (r - A z); z += O (r - A z)
// symmetric; two more operator applies per use. A must outlive the preconditioner.
class SymmetricProductPreconditioner final : public Preconditioner {
 public:
  SymmetricProductPreconditioner(const LinearOperator &A, std::unique_ptr<Preconditioner> outer,
                                 std::unique_ptr<Preconditioner> inner, std::string name);
  void apply(const Vector &r, Vector &z) const override;
  std::string name() const override { return name_; }

 private:
  const LinearOperator &A_;
  std::unique_ptr<Preconditioner> outer_, inner_;
  std::string name_;
  mutable Vector Az_, res_, tmp_;
};

} // namespace fibre
