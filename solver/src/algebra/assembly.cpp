#include "fibre/algebra/assembly.hpp"

#include "fibre/algebra/kernels.hpp"

namespace fibre {

SparseMatrix assemble_G(const ContactSystem &sys)
{
  const int rows = sys.rows();
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(std::size_t(sys.num_contacts()) * rows * 12);
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    for (int side = 0; side < (k.is_wall() ? 1 : 2); ++side) {
      // jacobian_block already zeroes masked rows; rows beyond rows() are padding.
      const Mat6 J = jacobian_block(sys, c, side);
      const int body = side == 0 ? k.a : k.b;
      for (int r = 0; r < rows; ++r)
        for (int j = 0; j < kBodyDofs; ++j)
          if (J(r, j) != 0.0)
            t.emplace_back(Eigen::Index(rows) * c + r, Eigen::Index(kBodyDofs) * body + j, J(r, j));
    }
  }
  SparseMatrix G(sys.contact_dofs(), sys.body_dofs());
  G.setFromTriplets(t.begin(), t.end());
  return G;
}

Vector assemble_inv_mass(const ContactSystem &sys)
{
  return sys.inv_mass();
}

Vector assemble_sigma(const ContactSystem &sys)
{
  return sys.sigma();
}

SparseMatrix assemble_A(const ContactSystem &sys, const std::vector<int> &owners)
{
  SparseMatrix G = assemble_G(sys);
  if (!owners.empty()) {
    std::vector<Eigen::Triplet<double>> to_owner;
    for (int i = 0; i < sys.num_bodies(); ++i)
      for (int d = 0; d < kBodyDofs; ++d)
        to_owner.emplace_back(kBodyDofs * i + d, kBodyDofs * owners[i] + d, 1.0);
    SparseMatrix P(sys.body_dofs(), sys.body_dofs());
    P.setFromTriplets(to_owner.begin(), to_owner.end());
    G = G * P;
  }
  SparseMatrix A = G * sys.inv_mass().asDiagonal() * SparseMatrix(G.transpose());
  // Diagonal entries always exist (Sigma > 0), so A's pattern holds the full diagonal.
  A += SparseMatrix(sys.sigma().asDiagonal());
  A.makeCompressed();
  return A;
}

SparseMatrix assemble_K(const ContactSystem &sys)
{
  const SparseMatrix G = assemble_G(sys);
  const SparseMatrix Gt = G.transpose();
  SparseMatrix K = Gt * sys.sigma().cwiseInverse().asDiagonal() * G;
  Vector m = Vector::Zero(sys.body_dofs());
  const Eigen::Index owned = Eigen::Index(kBodyDofs) * sys.num_owned_bodies();
  m.head(owned) = sys.inv_mass().head(owned).cwiseInverse();
  K += SparseMatrix(m.asDiagonal());
  K.makeCompressed();
  return K;
}

Vector assemble_rhs(const ContactSystem &sys)
{
  const SpookParams &p = sys.params();
  const double ups = p.upsilon();
  const int nb = sys.num_bodies();
  Vector v(sys.body_dofs()), f(sys.body_dofs());
  for (int i = 0; i < nb; ++i) {
    const Body &b = sys.bodies()[i];
    v.segment<3>(6 * i) = b.v;
    v.segment<3>(6 * i + 3) = b.omega;
    f.segment<3>(6 * i) = b.force;
    f.segment<3>(6 * i + 3) = b.torque;
  }
  const SparseMatrix G = assemble_G(sys);
  const Vector Gv = G * v;
  Vector rhs = -(1.0 - ups) * Gv - p.h * (G * sys.inv_mass().cwiseProduct(f));
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    const Eigen::Index row = Eigen::Index(sys.rows()) * c;
    const double ups_c = p.upsilon(p.damping_of(k));
    const std::array<double, kMaxRows> wall = wall_rows(k);
    for (int r = 0; r < sys.rows(); ++r) {
      const double ups_r = p.upsilon(p.damping_of(k, r));
      rhs[row + r] += (ups_r - ups) * Gv[row + r] + (1.0 - ups_r) * wall[r];
      if (r > 0 && k.elastic[r] && sys.row_active(row + r))
        rhs[row + r] += p.spring_term(k.spring[r], ups_r);
    }
    if (sys.row_active(row)) rhs[row] += p.gap_term(k, ups_c);
    if (sys.row_active(row) && k.implicit_normal) rhs[row] -= ups_c * (Gv[row] - wall[0]);
  }
  return rhs;
}

void upper_triplets(const SparseMatrix &S, std::vector<long> &rows, std::vector<long> &cols,
                    std::vector<double> &values)
{
  rows.clear();
  cols.clear();
  values.clear();
  for (Eigen::Index j = 0; j < S.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(S, j); it; ++it)
      if (it.row() <= it.col()) {
        rows.push_back(static_cast<long>(it.row()));
        cols.push_back(static_cast<long>(it.col()));
        values.push_back(it.value());
      }
}

} // namespace fibre
