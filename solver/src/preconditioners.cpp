#include "fibre/preconditioners.hpp"

#include <stdexcept>

namespace fibre {

const char *to_string(PrecondKind k)
{
  switch (k) {
    case PrecondKind::none: return "none";
    case PrecondKind::jacobi: return "jacobi";
    case PrecondKind::block: return "block";
    case PrecondKind::fibre: return "fibre";
    case PrecondKind::tree: return "tree";
  }
  return "?";
}

bool parse_precond(const std::string &s, PrecondKind &k)
{
  for (PrecondKind c : {PrecondKind::none, PrecondKind::jacobi, PrecondKind::block,
                        PrecondKind::fibre, PrecondKind::tree})
    if (s == to_string(c)) {
      k = c;
      return true;
    }
  return false;
}

namespace {

// z = D^-1 r with D a positive diagonal (stored inverted).
class DiagonalPreconditioner final : public Preconditioner {
 public:
  explicit DiagonalPreconditioner(Vector inv_diag) : inv_diag_(std::move(inv_diag)) {}
  void apply(const Vector &r, Vector &z) const override
  {
    z = inv_diag_.cwiseProduct(r);
  }
  std::string name() const override { return "jacobi"; }

 private:
  Vector inv_diag_;
};

// z = B^-1 r with B block diagonal, n x n blocks (n <= 6) stored as Cholesky factors. Blocks
// past `active` (ghost bodies) give zero.
class BlockPreconditioner final : public Preconditioner {
 public:
  BlockPreconditioner(int n, std::vector<double> factors, int active, Eigen::Index size)
      : n_(n), factors_(std::move(factors)), active_(active), size_(size)
  {
  }
  void apply(const Vector &r, Vector &z) const override
  {
    z.setZero(size_);
    for (int i = 0; i < active_; ++i) {
      const Eigen::Map<const Mat6> L(factors_.data() + 36 * std::size_t(i));
      Vec6 x = Vec6::Zero();
      x.head(n_) = r.segment(Eigen::Index(n_) * i, n_);
      L.triangularView<Eigen::Lower>().solveInPlace(x);
      L.triangularView<Eigen::Lower>().transpose().solveInPlace(x);
      z.segment(Eigen::Index(n_) * i, n_) = x.head(n_);
    }
  }
  std::string name() const override { return "block"; }

 private:
  int n_;
  std::vector<double> factors_;  // 36 per block: the 6x6 lower factor, column-major
  int active_;
  Eigen::Index size_;
};

void store_factor(const Mat6 &B, double *out)
{
  Eigen::LLT<Mat6> llt(B);
  if (llt.info() != Eigen::Success) throw std::runtime_error("block is not positive definite");
  Eigen::Map<Mat6> L(out);
  L = llt.matrixL();
}

std::unique_ptr<Preconditioner> contact_block(const ContactSystem &sys, bool scalar)
{
  const int nc = sys.num_contacts(), rows = sys.rows();
  if (scalar) {
    Vector inv(sys.contact_dofs());
    for (int c = 0; c < nc; ++c)
      inv.segment(Eigen::Index(rows) * c, rows) =
          diagonal_block(sys, c).diagonal().head(rows).cwiseInverse();
    return std::make_unique<DiagonalPreconditioner>(std::move(inv));
  }
  std::vector<double> f(36 * std::size_t(nc));
  for (int c = 0; c < nc; ++c) store_factor(diagonal_block(sys, c), f.data() + 36 * std::size_t(c));
  return std::make_unique<BlockPreconditioner>(rows, std::move(f), nc, sys.contact_dofs());
}

std::unique_ptr<Preconditioner> body_block(const ContactSystem &sys, bool scalar)
{
  const int owned = sys.num_owned_bodies();
  const std::vector<Mat6> K = body_diagonal_blocks(sys);
  if (scalar) {
    Vector inv = Vector::Zero(sys.body_dofs());
    for (int i = 0; i < owned; ++i) inv.segment<6>(6 * i) = K[i].diagonal().cwiseInverse();
    return std::make_unique<DiagonalPreconditioner>(std::move(inv));
  }
  std::vector<double> f(36 * std::size_t(owned));
  for (int i = 0; i < owned; ++i) store_factor(K[i], f.data() + 36 * std::size_t(i));
  return std::make_unique<BlockPreconditioner>(6, std::move(f), owned, sys.body_dofs());
}

}  // namespace

std::unique_ptr<Preconditioner> make_preconditioner(Form form, const ContactSystem &sys,
                                                    const Exchange &, const PrecondOptions &opt,
                                                    FibreStats *)
{
  switch (opt.kind) {
    case PrecondKind::none: return std::make_unique<IdentityPreconditioner>();
    case PrecondKind::jacobi:
    case PrecondKind::block: {
      const bool scalar = opt.kind == PrecondKind::jacobi;
      return form == Form::contact ? contact_block(sys, scalar) : body_block(sys, scalar);
    }
    case PrecondKind::fibre:
    case PrecondKind::tree: break;
  }
  throw std::invalid_argument(std::string("preconditioner '") + to_string(opt.kind) +
                              "' is not available yet");
}

}  // namespace fibre
