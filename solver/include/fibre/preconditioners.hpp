// The preconditioner family of design.md section 3 in both forms, and its factory.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "fibre/fibres.hpp"
#include "fibre/preconditioner.hpp"

namespace fibre {

enum class PrecondKind { none, jacobi, block, fibre, tree };
const char *to_string(PrecondKind k);
bool parse_precond(const std::string &s, PrecondKind &k);

struct PrecondOptions {
  PrecondKind kind = PrecondKind::block;
  EdgeWeight weight = EdgeWeight::z;
  // Last step's normal impulse per contact (size num_contacts), for EdgeWeight::impulse.
  const Vector *impulses = nullptr;
};

// Builds the preconditioner for `form` on `sys`. For fibre/tree the fibres or forest are
// built here from this process's own contacts; `stats` (optional) receives their figures.
std::unique_ptr<Preconditioner> make_preconditioner(Form form, const ContactSystem &sys,
                                                    const Exchange &ex,
                                                    const PrecondOptions &opt,
                                                    FibreStats *stats = nullptr);

}  // namespace fibre
