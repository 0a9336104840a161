#include "fibre/algebra/cones.hpp"

#include <algorithm>

#include <cmath>

#include "fibre/algebra/kernels.hpp"
#include "fibre/algebra/spook.hpp"

namespace fibre {

Cones::Cones(const ContactSystem &sys)
    : rows_(sys.rows()), coeff_(std::size_t(sys.num_contacts()) * 3, 0.0)
{
  const double h = sys.params().h;
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    for (int cone = 0; cone < num_cones(rows_); ++cone)
      coeff_[3 * std::size_t(c) + cone] =
          cone_coefficient(k.friction, sys.effective_radius(c), cone);
    if (!(k.pull > 0)) continue;
    if (pull_.empty()) pull_.assign(std::size_t(sys.num_contacts()), 0.0);
    pull_[c] = h * k.pull;
  }
}

Cones Cones::frictionless(const ContactSystem &sys)
{
  Cones cones(sys);
  std::fill(cones.coeff_.begin(), cones.coeff_.end(), 0.0);
  // a joint stays bilateral: the recovery moves a clump as one body
  bool joints = false;
  for (int c = 0; c < sys.num_contacts(); ++c) {
    if (!sys.contacts()[c].is_joint()) {
      if (!cones.pull_.empty()) cones.pull_[c] = 0.0;
      continue;
    }
    joints = true;
    for (int cone = 0; cone < num_cones(cones.rows_); ++cone)
      cones.coeff_[3 * std::size_t(c) + cone] = 1.0;
  }
  if (!joints) cones.pull_.clear();
  return cones;
}

std::vector<Vec6> row_scales(const ContactSystem &sys)
{
  std::vector<Vec6> diagonal(sys.num_contacts());
  for (int c = 0; c < sys.num_contacts(); ++c) diagonal[c] = diagonal_entries(sys, c);
  return row_scales(diagonal, sys.rows());
}

std::vector<Vec6> row_scales(const std::vector<Vec6> &diagonal, int rows)
{
  const int nc = static_cast<int>(diagonal.size());
  std::vector<Vec6> scale(nc, Vec6::Ones());
  for (int c = 0; c < nc; ++c) {
    const Vec6 &D = diagonal[c];
    scale[c][0] = D[0];
    for (int k = 0; k < num_cones(rows); ++k) {
      const Cone &cone = kCones[k];
      double d = D[cone.first];
      if (cone.size == 2) d = std::max(d, D[cone.first + 1]);
      for (int i = 0; i < cone.size; ++i) scale[c][cone.first + i] = d;
    }
  }
  return scale;
}

double complementarity(const ContactSystem &sys, const Exchange &ex, const Cones &cones,
                       const Vector &b, const Vector &lambda, const std::vector<Vec6> &scale)
{
  const int rows = sys.rows();
  Vector G_dv;
  g_apply(sys, velocity_change(sys, ex, lambda), G_dv);
  const Vector rho = b - G_dv - sys.sigma().cwiseProduct(lambda);
  Vector trial = lambda;
  for (int c = 0; c < sys.num_contacts(); ++c)
    for (int i = 0; i < rows; ++i)
      trial[Eigen::Index(rows) * c + i] += rho[Eigen::Index(rows) * c + i] / scale[c][i];
  for (int c = 0; c < sys.num_contacts(); ++c)
    cones.project(trial.data() + Eigen::Index(rows) * c, c);
  double sums[2] = {(trial - lambda).squaredNorm(), lambda.squaredNorm()};
  ex.sum(sums, 2);
  if (!(sums[1] > 0)) return sums[0] > 0 ? 1.0 : 0.0;
  return std::sqrt(sums[0] / sums[1]);
}

} // namespace fibre
