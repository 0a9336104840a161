#include "fibre/step/recovery.hpp"

#include <algorithm>

#include "fibre/algebra/cones.hpp"
#include "fibre/algebra/kernels.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/solvers/pgs.hpp"

namespace fibre {

namespace {

// The target opening speed of each normal row: a penetration's overlap left after the step (a
// rigid row's whole overlap, an elastic row's penetration as far as the overlap still holds
// it), at most max_recovery; an open contact may close by its gap; a touching one not further.
// (Gv: G v_plus, the velocities after the step)
Vector recovery_rhs(const ContactSystem &sys, const Vector &Gv, double span)
{
  const SpookParams &p = sys.params();
  const int rows = sys.rows();
  Vector b = Vector::Zero(sys.contact_dofs());
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    const Eigen::Index row = Eigen::Index(rows) * c;
    const double gap = gap_after(k, p.h, Gv[row], sys.walls_move());
    const double left = k.elastic[0] ? std::min(k.penetration, -gap) : -gap;
    if (p.split_penetration(k))
      b[row] = std::min(std::max(left, 0.0) / span, p.max_recovery);
    else if (k.is_joint()) // a clump moves as one body
      b[row] = 0.0;
    else
      b[row] = std::min(-gap / span, 0.0);
  }
  return b;
}

// The system's elastic normal rows made rigid, in place, for the displacement's solve, and
// restored (compliances, Sigma and row mask bit for bit) when this goes: the displacement
// neither compresses a law's spring (a caged sphere's neighbours, pushed into theirs, stored
// the energy that threw the cage apart at 11 m/s) nor leaves Sigma's share of a penetration's
// opening. A rigid row's Sigma is 1e-4 of its G M^-1 G^T (compliance auto's is about 0.01).
// In place, not a copy: a copy of the system (its contacts, kinematics and bodies) was a
// fifth of a settling silo's peak heap (42 of 212 MB).
class RigidNormalRows {
 public:
  explicit RigidNormalRows(ContactSystem &sys) : sys_(sys)
  {
    const std::vector<Contact> &contacts = sys.contacts();
    if (std::none_of(contacts.begin(), contacts.end(),
                     [](const Contact &c) { return c.elastic[0]; }))
      return;
    mask_ = sys.row_mask();
    if (!mask_.empty()) sys.set_row_mask(std::vector<unsigned char>(sys.contact_dofs(), 1));
    const double h = sys.params().h;
    saved_.resize(contacts.size());
    sys.edit_compliances([&](std::vector<Contact> &edit) {
      for (std::size_t c = 0; c < edit.size(); ++c) {
        saved_[c] = edit[c].compliance[0];
        const std::array<Vec6, 2> &sides = sys.diagonal_sides(static_cast<int>(c));
        if (edit[c].elastic[0]) edit[c].compliance[0] = 1e-4 * h * h * (sides[0][0] + sides[1][0]);
      }
    });
  }
  ~RigidNormalRows()
  {
    if (saved_.empty()) return;
    sys_.edit_compliances([this](std::vector<Contact> &edit) {
      for (std::size_t c = 0; c < edit.size(); ++c) edit[c].compliance[0] = saved_[c];
    });
    if (!mask_.empty()) sys_.set_row_mask(mask_);
  }
  RigidNormalRows(const RigidNormalRows &) = delete;
  RigidNormalRows &operator=(const RigidNormalRows &) = delete;

 private:
  ContactSystem &sys_;
  std::vector<double> saved_;
  std::vector<unsigned char> mask_;
};

// Whether the displacement dx closes other contacts (an open one beyond its gap after the step,
// a touching or split one at all) by at least kShuffle of what it opens of the split
// penetrations: a jammed pack (more spheres than its box holds) has no displacement that opens
// them, and the sweeps' unconverged impulses moved overlap from contact to contact (closed /
// opened 0.99 to 1 a step) until the springs of the deepened contacts threw 4 of 125 spheres
// out of the box. Where there is room the ratio is at most 0.41 (a deposit into a bed, spheres
// created inside one). Collective.
constexpr double kShuffle = 0.7;
bool shuffles(const ContactSystem &sys, const Exchange &ex, const Vector &Gv, const Vector &dx)
{
  const SpookParams &p = sys.params();
  const int rows = sys.rows();
  Vector opening;
  g_apply(sys, dx, opening);
  double sums[2] = {0.0, 0.0}; // opened, closed
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    const Eigen::Index row = Eigen::Index(rows) * c;
    const bool split = p.split_penetration(k);
    const double gap = gap_after(k, p.h, Gv[row], sys.walls_move());
    if (split) sums[0] += std::max(opening[row], 0.0);
    sums[1] += std::max(-opening[row] - (split ? 0.0 : std::max(gap, 0.0)), 0.0);
  }
  ex.sum(sums, 2);
  return sums[1] >= kShuffle * sums[0];
}

} // namespace

long split_penetrations(const ContactSystem &sys, const Exchange &ex)
{
  const SpookParams &p = sys.params();
  double count =
      static_cast<double>(std::count_if(sys.contacts().begin(), sys.contacts().end(),
                                        [&p](const Contact &c) { return p.split_penetration(c); }));
  ex.sum(&count, 1);
  return static_cast<long>(count);
}

Recovery recovery_displacement(ContactSystem &sys, const Exchange &ex, const Vector &v_plus,
                               double span, Vector &dx, int max_sweeps)
{
  Recovery recovery;
  recovery.split = split_penetrations(sys, ex);
  if (recovery.split == 0) return recovery;
  Vector Gv;
  g_apply(sys, v_plus, Gv);
  const Vector b = recovery_rhs(sys, Gv, span);
  {
    const RigidNormalRows rigid(sys);
    const Cones frictionless = Cones::frictionless(sys);
    Vector mu = Vector::Zero(sys.contact_dofs());
    PgsControl control;
    control.max_sweeps = max_sweeps;
    control.tol = 1e-3;
    pgs(sys, ex, frictionless, b, row_scales(sys), mu, control);
    dx = velocity_change(sys, ex, mu);
  }
  const double reach = span * sys.params().max_recovery;
  double fastest = 0.0;
  for (int i = 0; i < sys.num_bodies(); ++i) {
    Eigen::Ref<Vector> body = dx.segment(6 * Eigen::Index(i), 6);
    body.tail<3>().setZero();
    fastest = std::max(fastest, span * body.head<3>().norm());
  }
  ex.max(&fastest, 1);
  dx *= fastest > reach ? span * reach / fastest : span;
  recovery.outcome = Recovery::Outcome::opened;
  if (shuffles(sys, ex, Gv, dx)) { // no room: the penetrations stay
    dx.setZero();
    recovery.outcome = Recovery::Outcome::refused;
  }
  return recovery;
}

void take_opening(const ContactSystem &sys, const Vector &dx,
                  std::vector<std::array<double, kMaxRows>> &springs)
{
  if (springs.size() != std::size_t(sys.num_contacts())) return;
  const SpookParams &p = sys.params();
  Vector opening;
  g_apply(sys, dx, opening);
  const int rows = sys.rows();
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    if (k.elastic[0] && p.split_penetration(k))
      springs[c][0] = std::max(0.0, springs[c][0] - opening[Eigen::Index(rows) * c]);
  }
}

} // namespace fibre
