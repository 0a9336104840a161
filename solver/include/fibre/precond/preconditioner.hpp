// Preconditioners: one small interface, setup from the system, apply to a vector.
// All are symmetric positive definite, in either form (doc/design.md section 3).
#pragma once

#include <memory>
#include <string>

#include "fibre/core/system.hpp"

namespace fibre {

class Preconditioner {
 public:
  virtual ~Preconditioner() = default;
  // z = P^-1 r. Vectors live in the operator's space (contact or body).
  virtual void apply(const Vector &r, Vector &z) const = 0;
  virtual std::string name() const = 0;
};

// The identity.
class IdentityPreconditioner final : public Preconditioner {
 public:
  void apply(const Vector &r, Vector &z) const override { z = r; }
  std::string name() const override { return "none"; }
};

} // namespace fibre
