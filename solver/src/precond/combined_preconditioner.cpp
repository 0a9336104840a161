#include "fibre/precond/combined_preconditioner.hpp"

#include <utility>

namespace fibre {

AveragePreconditioner::AveragePreconditioner(std::unique_ptr<Preconditioner> first,
                                             std::unique_ptr<Preconditioner> second,
                                             std::string name)
    : first_(std::move(first)), second_(std::move(second)), name_(std::move(name))
{
}

void AveragePreconditioner::apply(const Vector &r, Vector &z) const
{
  first_->apply(r, z);
  second_->apply(r, tmp_);
  z = 0.5 * (z + tmp_);
}

SymmetricProductPreconditioner::SymmetricProductPreconditioner(
    const LinearOperator &A, std::unique_ptr<Preconditioner> outer,
    std::unique_ptr<Preconditioner> inner, std::string name)
    : A_(A), outer_(std::move(outer)), inner_(std::move(inner)), name_(std::move(name))
{
}

void SymmetricProductPreconditioner::apply(const Vector &r, Vector &z) const
{
  outer_->apply(r, z);
  A_.apply(z, Az_);
  res_ = r - Az_;
  inner_->apply(res_, tmp_);
  z += tmp_;
  A_.apply(z, Az_);
  res_ = r - Az_;
  outer_->apply(res_, tmp_);
  z += tmp_;
}

} // namespace fibre
