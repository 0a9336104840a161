#include "fibre/solvers/pgs.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>

#include "fibre/algebra/contact_rows.hpp"
#include "fibre/algebra/kernels.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/precond/fibre_blocks.hpp"
#include "fibre/solvers/anderson.hpp"
#include "fibre/solvers/joint_blocks.hpp"
#include "fibre/solvers/sweep_groups.hpp"

namespace fibre {

void PgsResult::record(double change, bool full)
{
  changes.push_back(change);
  if (!full) return; // focused sweeps: the rate and the estimate follow the full ones
  last_change = change;
  const int s = static_cast<int>(changes.size()) - 1;
  // the latest full sweep at least kRateWindow sweeps back (plain sweeps: exactly that far)
  for (auto at = full_sweeps.rbegin(); at != full_sweeps.rend(); ++at)
    if (*at <= s - kRateWindow) {
      const double first = changes[*at];
      contraction = first > 0 ? std::pow(change / first, 1.0 / (s - *at)) : 1.0;
      break;
    }
  full_sweeps.push_back(s);
}

double PgsResult::error_estimate() const
{
  return contact_scale * impulse_estimate();
}

double PgsResult::impulse_estimate() const
{
  if (last_change == 0) return 0;
  // Anderson: the error is (I - J)^-1 f, at most |f| over the smallest singular value of
  // I - J; the history's estimate of it is an upper bound (a column, not the subspace's
  // minimum). Measured (bench/README.md, "Anderson acceleration"): the minimum over one
  // history left errors up to 2.6 |f| / sigma; over the whole step and doubled, they stayed
  // within plain sweeps'.
  if (singular_value >= 0)
    return std::isfinite(singular_value) && singular_value > 0
               ? kAndersonSafety * mixed_change / singular_value
               : INFINITY;
  if (!(contraction < 1)) return INFINITY;
  return last_change * contraction / (1 - contraction);
}

double PgsResult::predicted_sweeps(double accuracy) const
{
  const int n = static_cast<int>(full_sweeps.size());
  if (n <= kPredictSweeps) return -1;
  const double now = changes[full_sweeps[n - 1]],
               then = changes[full_sweeps[n - 1 - kPredictSweeps]];
  if (!(now > 0)) return 0;
  const double span = full_sweeps[n - 1] - full_sweeps[n - 1 - kPredictSweeps];
  const double rate = then > 0 ? std::pow(now / then, 1.0 / span) : 1.0;
  if (!(rate < 1)) return INFINITY;
  const double estimate = std::min(error_estimate(), now * rate / (1 - rate));
  if (!(estimate > accuracy)) return 0;
  return std::log(accuracy / estimate) / std::log(rate);
}

void PgsResult::append(PgsResult then)
{
  for (int &s : then.full_sweeps) s += static_cast<int>(changes.size());
  then.changes.insert(then.changes.begin(), changes.begin(), changes.end());
  then.sweeps += sweeps;
  then.visits += visits;
  then.slow_restarts += slow_restarts;
  *this = std::move(then);
}

namespace {

// One sweep over the contacts `list` (in order; all of them when null, else `count`): each
// moves to lambda_c + (b_c - G_c dv - Sigma_c lambda_c) / scale_c and is projected, and dv
// follows at once. Adds ||change||^2 and ||lambda||^2 (local) of the contacts it visits to
// norms; with `changes`, it stores each one's change^2 there. The rows of G are applied in
// their structured form (contact_rows.hpp).
template <int R>
void sweep(const ContactSystem &sys, const Cones &cones, const Vector &b, const double *inv_mass,
           const std::vector<Vec6> &inv_scale, const std::vector<int> &owners, const int *list,
           int count, Vector &lambda, Vector &dv, double norms[2], double *changes)
{
  const int *pairs = sys.body_pairs();
  const double *kin = sys.num_contacts() > 0 ? sys.kinematics(0).frame.data() : nullptr;
  const double *sigma = sys.sigma().data();
  double *l = lambda.data(), *w = dv.data();
  for (int k = 0; k < count; ++k) {
    const int c = list ? list[k] : k;
    const double *q = kin + 15 * std::size_t(c);
    int ia = pairs[2 * std::size_t(c)], ib = pairs[2 * std::size_t(c) + 1];
    if (!owners.empty()) { // a periodic image moves with its body
      ia = owners[ia];
      if (ib >= 0) ib = owners[ib];
    }
    double *wa = w + 6 * std::size_t(ia), *wb = ib >= 0 ? w + 6 * std::size_t(ib) : nullptr;
    double u[6], old[6], delta[6] = {0, 0, 0, 0, 0, 0};
    contact_velocity<R>(q, q + 9, q + 12, wa, wb, u);
    double *lc = l + std::size_t(R) * c;
    const std::size_t at = std::size_t(R) * c;
    for (int i = 0; i < R; ++i) {
      old[i] = lc[i];
      lc[i] += (b[at + i] - u[i] - sigma[at + i] * old[i]) * inv_scale[c][i];
    }
    cones.project_rows<R>(lc, c);
    double change2 = 0;
    for (int i = 0; i < R; ++i) {
      delta[i] = lc[i] - old[i];
      change2 += delta[i] * delta[i];
      norms[1] += lc[i] * lc[i];
    }
    norms[0] += change2;
    if (changes) changes[c] = change2;
    if (change2 == 0) continue; // an open contact that stays open moves no body
    double ya[6] = {0, 0, 0, 0, 0, 0}, yb[6] = {0, 0, 0, 0, 0, 0};
    contact_impulse<R>(q, q + 9, q + 12, delta, ya, wb ? yb : nullptr);
    const double *ma = inv_mass + 6 * std::size_t(ia);
    for (int d = 0; d < 6; ++d) wa[d] += ma[d] * ya[d];
    if (wb) {
      const double *mb = inv_mass + 6 * std::size_t(ib);
      for (int d = 0; d < 6; ++d) wb[d] += mb[d] * yb[d];
    }
  }
}

// A body's kBodyDofs entries of a per-body vector.
template <class V> auto body_entries(V &v, int body)
{
  return v.template segment<kBodyDofs>(kBodyDofs * Eigen::Index(body));
}

// Per local body, whether this process's contacts move it (an image's velocity is its body's).
std::vector<char> touched_bodies(const ContactSystem &sys, const Exchange &ex)
{
  const std::vector<int> &owners = ex.local_owners();
  const int *pairs = sys.body_pairs();
  std::vector<char> touched(sys.num_bodies(), 0);
  for (int e = 0; e < 2 * sys.num_contacts(); ++e)
    if (pairs[e] >= 0) touched[owner_of(owners, pairs[e])] = 1;
  return touched;
}

// Per body (6 entries each, on its owner and its ghosts): how many processes' contacts move
// it (`total`), and how many of those have this process's colour (`split`, at least 1: mass
// splitting's share, pgs.hpp). `total` is empty where no body is shared, `split` where no two
// processes of one colour share one.
struct BodyShares {
  Vector total, split;
};
BodyShares body_shares(const std::vector<char> &touched, const Exchange &ex, int colours,
                       int colour)
{
  const Eigen::Index n = Eigen::Index(touched.size());
  Vector count = Vector::Zero(Eigen::Index(kBodyDofs) * n); // entry k: the processes of colour k
  for (Eigen::Index body = 0; body < n; ++body)
    if (touched[body]) count[kBodyDofs * body + colour] = 1.0;
  ex.reverse_sum(count);
  ex.forward(count);
  BodyShares shares{Vector(count.size()), Vector(count.size())};
  for (Eigen::Index body = 0; body < n; ++body) {
    const double *c = count.data() + kBodyDofs * body;
    const double total = std::accumulate(c, c + colours, 0.0);
    shares.total.segment<kBodyDofs>(kBodyDofs * body).setConstant(std::max(1.0, total));
    shares.split.segment<kBodyDofs>(kBodyDofs * body).setConstant(std::max(1.0, c[colour]));
  }
  if (!(ex.max(n ? shares.total.maxCoeff() : 1.0) > 1.0)) return BodyShares();
  if (!(ex.max(n ? shares.split.maxCoeff() : 1.0) > 1.0)) shares.split = Vector();
  return shares;
}

// The contacts that a full sweep moved by at least kFocusShare of its mean change^2: those
// left out moved by less than kFocusShare of the sweep's change^2 together.
constexpr double kFocusShare = 1e-3;
void focus_list(const std::vector<double> &changes, double total, std::vector<int> &list)
{
  list.clear();
  const double floor = changes.empty() ? 0.0 : kFocusShare * total / double(changes.size());
  for (std::size_t c = 0; c < changes.size(); ++c)
    if (changes[c] >= floor) list.push_back(static_cast<int>(c));
}

// The contacts of each colour's phase (colours > 1), in their order: those on a body that
// other processes' contacts move too (shares > 1) in this process's phase, the others dealt out
// evenly over all phases, so that every process sweeps about as many in each.
std::vector<std::vector<int>> colour_phases(const ContactSystem &sys, const Exchange &ex,
                                            const Vector &shares, int colours, int colour)
{
  const std::vector<int> &owners = ex.local_owners();
  const auto shared = [&](int body) {
    return body >= 0 && shares[Eigen::Index(kBodyDofs) * owner_of(owners, body)] > 1.0;
  };
  const int nc = sys.num_contacts();
  std::vector<char> boundary(nc);
  int inner = 0;
  for (int c = 0; c < nc; ++c) {
    const Contact &k = sys.contacts()[c];
    boundary[c] = shared(k.a) || shared(k.b);
    inner += !boundary[c];
  }
  std::vector<std::vector<int>> phases(colours);
  int seen = 0;
  for (int c = 0; c < nc; ++c)
    if (boundary[c])
      phases[colour].push_back(c);
    else
      phases[std::size_t(long(seen++) * colours / std::max(inner, 1))].push_back(c);
  return phases;
}

// One call of pgs: the sweeps' process layout and masses, their groups, Anderson's history and
// the stop and stall rules over the sweeps of one solve.
class PgsRun {
 public:
  PgsRun(const ContactSystem &sys, const Exchange &ex, const Cones &cones, const Vector &b,
         const std::vector<Vec6> &scale, Vector &lambda, const PgsControl &control)
      : sys_(sys), ex_(ex), cones_(cones), b_(b), control_(control), lambda_(lambda),
        nc_(sys.num_contacts()), rows_(sys.rows()), halo_(ex.has_halo()),
        // the blocks' corrections are not part of the sweeps' steps, and measured with them
        // the combination diverged on a stiff pile: plain sweeps only
        accelerate_(control.anderson > 0 && !control.nonlinear_cg && !control.fibre_blocks),
        focus_(control.focus_sweeps > 0 && !control.nonlinear_cg && !control.fibre_blocks &&
               !accelerate_),
        anderson_(std::max(control.anderson, 1), ex), period_(std::max(control.anderson_period, 1))
  {
    layout(scale);
    block_joints();
    // the blocks read their bound rows from feasible impulses
    if (control_.fibre_blocks)
      for (int c = 0; c < nc_; ++c) cones_.project(lambda_.data() + Eigen::Index(rows_) * c, c);
    dv_ = velocity_change(sys_, ex_, lambda_);
    // Each phase's changes go to the other processes as `moved_`, from dv_start_, its start: on
    // the halo's bodies only where it names them (a few dozen, where a full vector has every
    // ghost).
    halo_bodies_ = halo_ ? copies_->bodies() : nullptr;
    if (halo_) {
      dv_start_ = dv_;
      moved_ = Vector::Zero(dv_.size());
    }
    if (control_.fibre_blocks) {
      Vector normal(nc_);
      for (int c = 0; c < nc_; ++c) normal[c] = lambda_[Eigen::Index(rows_) * c];
      blocks_ = std::make_unique<FibreBlocks>(sys_, ex_.local_owners(), cones_,
                                              control_.block_weight, &normal);
    }
    grouped_ = control_.cache ? &control_.cache->grouped : &own_;
    prepare_groups();
    contact_changes_.resize(focus_ ? nc_ : 0);
  }

  PgsResult run()
  {
    for (int s = 0; s < control_.max_sweeps; ++s)
      if (sweep(s)) {
        if (res_.reason == StopReason::non_finite) return res_; // lambda is the checkpoint
        break;
      }
    if (combination_) lambda_ = anderson_.sweep_result();
    if (control_.nonlinear_cg) // the last step along the direction may have left the cones
      for (int c = 0; c < nc_; ++c) cones_.project(lambda_.data() + Eigen::Index(rows_) * c, c);
    return res_;
  }

 private:
  // Impulses to fall back on when a sweep turns non-finite: a copy every kCheckpointSweeps
  // sweeps, not every sweep (stiff steps take hundreds), and every sweep for nonlinear CG,
  // whose direction is the sweep's change.
  static constexpr int kCheckpointSweeps = 16;

  void layout(const std::vector<Vec6> &scale);
  void block_joints();
  void prepare_groups();
  void keep_start();
  void sweep_and_sum(const int *visit, int n, GroupedSweep *group, const JointBlocks *joints,
                     double *norms, double *changes);
  bool sweep(int s);
  bool stop_rule(bool full, const double *norms);
  bool stalled();
  bool slow() const;
  void cg_step(int s, double change2);

  const ContactSystem &sys_;
  const Exchange &ex_;
  const Cones &cones_;
  const Vector &b_;
  const PgsControl &control_;
  Vector &lambda_;
  PgsResult res_;
  const int nc_, rows_;
  const bool halo_; // else the round trip of the sweeps' changes is the identity
  const bool accelerate_, focus_;
  // the process layout (layout())
  std::unique_ptr<Exchange::Halo> copies_;
  BodyShares shares_;
  std::vector<std::vector<int>> phases_;
  bool coloured_ = false;
  // the clumps' joints in blocks, per phase (one without colours), and without colours the
  // contacts the full sweeps visit one at a time or in groups (the rest)
  std::vector<JointBlocks> joints_;
  std::vector<int> free_;
  Vector split_inv_mass_;
  std::vector<Vec6> inv_scale_;
  const double *inv_mass_ = nullptr;
  // the sweeps' velocity change, and its exchange
  Vector dv_, dv_start_, moved_;
  const std::vector<int> *halo_bodies_ = nullptr;
  Vector lambda_start_;
  double best_ = INFINITY;
  int since_best_ = 0;
  // Anderson's combination can cycle where plain sweeps converge (a LIGGGHTS heap's step: its
  // rotations drifted off again after sweep 900). After kAndersonStallSweeps sweeps without a
  // new smallest change the sweeps go on plain from the best checkpointed sweep.
  bool plain_ = false, have_best_ = false; // have_best_: alike on every process
  Vector lambda_best_;
  Vector direction_, change_; // nonlinear CG
  double last_change2_ = 0;
  std::unique_ptr<FibreBlocks> blocks_;
  std::vector<std::unique_ptr<GroupedSweep>> own_;
  std::vector<std::unique_ptr<GroupedSweep>> *grouped_ = nullptr;
  Anderson anderson_;
  const int period_;
  bool combination_ = false; // lambda is Anderson's start, not a sweep's result
  std::vector<double> contact_changes_;
  std::vector<int> focus_contacts_;
};

// Two process colours (Exchange::Halo::colours): the contacts on bodies that other processes'
// contacts move too are swept in their process's colour's phase of the sweep, so that a body
// that processes of two colours share moves as on one process. A body that processes of one
// colour share (all of them without colours) is split among them: each sees a copy of inverse
// mass split / m (mass splitting). Neither with fibre blocks, whose corrections move their
// bodies at their own mass, nor with nonlinear CG, whose steps along its direction the split
// slowed (12 of test_fix_solvers' 60 steps at np 2 unconverged); focused sweeps split only.
void PgsRun::layout(const std::vector<Vec6> &scale)
{
  const std::vector<char> touched = halo_ ? touched_bodies(sys_, ex_) : std::vector<char>();
  const bool shareable = halo_ && !control_.fibre_blocks && !control_.nonlinear_cg;
  const bool colouring = shareable && !focus_;
  copies_ = halo_ ? ex_.halo(touched, colouring) : nullptr;
  // (the counts per colour travel in a body's kBodyDofs entries)
  const int colours = colouring && copies_->colours() <= kBodyDofs ? copies_->colours() : 1;
  const int colour = colours > 1 ? copies_->colour() : 0;
  shares_ = shareable ? body_shares(touched, ex_, colours, colour) : BodyShares();
  const Vector &split = shares_.split;
  if (colours > 1 && shares_.total.size())
    phases_ = colour_phases(sys_, ex_, shares_.total, colours, colour);
  coloured_ = !phases_.empty();
  inv_scale_.resize(scale.size());
  if (split.size()) {
    split_inv_mass_ = sys_.inv_mass().cwiseProduct(split);
    const std::vector<int> &owners = ex_.local_owners();
    const auto split_of = [&](int body) {
      if (body < 0) return 1.0;
      return split[Eigen::Index(kBodyDofs) * owner_of(owners, body)];
    };
    std::vector<Vec6> diagonal(nc_);
    for (int c = 0; c < nc_; ++c) {
      const Contact &k = sys_.contacts()[c];
      diagonal[c] = diagonal_entries(sys_, c, split_of(k.a), split_of(k.b));
    }
    const std::vector<Vec6> split_scale = row_scales(diagonal, rows_);
    for (int c = 0; c < nc_; ++c) inv_scale_[c] = split_scale[c].cwiseInverse();
  } else {
    for (std::size_t c = 0; c < scale.size(); ++c) inv_scale_[c] = scale[c].cwiseInverse();
  }
  inv_mass_ = split.size() ? split_inv_mass_.data() : sys_.inv_mass().data();
}

// The clumps' joints in blocks (joint_blocks.hpp), out of each phase's or the full sweeps' lists
void PgsRun::block_joints()
{
  const std::vector<Contact> &contacts = sys_.contacts();
  if (std::none_of(contacts.begin(), contacts.end(), [](const Contact &k) { return k.is_joint(); }))
    return;
  if (coloured_) {
    for (std::vector<int> &phase : phases_) {
      joints_.emplace_back(sys_, ex_.local_owners(), inv_mass_, &phase);
      phase = joints_.back().others();
    }
    return;
  }
  joints_.emplace_back(sys_, ex_.local_owners(), inv_mass_, nullptr);
  if (joints_.back().empty())
    joints_.clear();
  else
    free_ = joints_.back().others();
}

// Four contacts at a time where the processor can (sweep_groups.hpp): the full sweeps, or each
// colour phase; not the focused sweeps' lists (kept in control.cache while the kinematics hold:
// the same contacts, phases and masses)
void PgsRun::prepare_groups()
{
  std::vector<std::unique_ptr<GroupedSweep>> &grouped = *grouped_;
  const bool split = shares_.split.size() > 0;
  if (control_.grouped && !focus_ && grouped_sweeps_available()) {
    const std::size_t wanted = coloured_ ? phases_.size() : 1;
    const bool kept = control_.cache && control_.cache->kinematics == sys_.kinematics_id() &&
                      control_.cache->split_masses == split && grouped.size() == wanted &&
                      sys_.row_mask().empty();
    if (kept) {
      for (const std::unique_ptr<GroupedSweep> &group : grouped)
        group->refresh(sys_, cones_, b_, inv_scale_);
    } else {
      grouped.clear();
      if (coloured_)
        for (const std::vector<int> &phase : phases_)
          grouped.push_back(std::make_unique<GroupedSweep>(sys_, cones_, b_, inv_mass_, inv_scale_,
                                                           ex_.local_owners(), &phase));
      else
        grouped.push_back(std::make_unique<GroupedSweep>(sys_, cones_, b_, inv_mass_, inv_scale_,
                                                         ex_.local_owners(),
                                                         joints_.empty() ? nullptr : &free_));
      if (control_.cache) {
        control_.cache->kinematics = sys_.row_mask().empty() ? sys_.kinematics_id() : 0;
        control_.cache->split_masses = split;
      }
    }
  } else {
    grouped.clear();
    if (control_.cache) control_.cache->kinematics = 0;
  }
}

void PgsRun::keep_start()
{
  if (!halo_bodies_) {
    dv_start_ = dv_;
    return;
  }
  for (const int body : *halo_bodies_) body_entries(dv_start_, body) = body_entries(dv_, body);
}

// Every process's updates on every body: the sum of the local changes, owners and ghosts (each
// copy's change at the body's own mass); with colours after each colour's phase.
void PgsRun::sweep_and_sum(const int *visit, int n, GroupedSweep *group, const JointBlocks *joints,
                           double *norms, double *changes)
{
  if (group) {
    group->sweep(lambda_, dv_, norms);
    visit = group->singles().data(); // then the rest one at a time
    n = static_cast<int>(group->singles().size());
  }
  if (rows_ == 6)
    fibre::sweep<6>(sys_, cones_, b_, inv_mass_, inv_scale_, ex_.local_owners(), visit, n, lambda_,
                    dv_, norms, changes);
  else
    fibre::sweep<3>(sys_, cones_, b_, inv_mass_, inv_scale_, ex_.local_owners(), visit, n, lambda_,
                    dv_, norms, changes);
  if (joints) joints->solve(b_, lambda_, dv_, norms, norms[2]);
  if (!halo_) return;
  const Vector &split = shares_.split;
  if (!halo_bodies_) {
    moved_ = dv_ - dv_start_;
    if (split.size()) moved_.array() /= split.array();
    copies_->sum_copies(moved_);
    dv_ = dv_start_ + moved_;
    return;
  }
  for (const int body : *halo_bodies_) {
    body_entries(moved_, body) = body_entries(dv_, body) - body_entries(dv_start_, body);
    if (split.size()) body_entries(moved_, body).array() /= body_entries(split, body).array();
  }
  copies_->sum_copies(moved_);
  for (const int body : *halo_bodies_)
    body_entries(dv_, body) = body_entries(dv_start_, body) + body_entries(moved_, body);
}

// Sweep s; true where the sweeps end (converged, stagnated or non-finite).
bool PgsRun::sweep(int s)
{
  // dv follows this process's updates; `moved` collects them for the other processes.
  if (halo_) keep_start();
  if (control_.nonlinear_cg || s % kCheckpointSweeps == 0) lambda_start_ = lambda_;
  if (blocks_) blocks_->correct(b_, lambda_, dv_);
  double norms[3] = {0, 0, 0}; // ||change||^2, ||lambda||^2, the joints' ||lambda||^2
  // focused: the first sweep is full, then every (P + 1)-th counted from min_sweeps (so the
  // rules can stop where plain sweeps would); the P between visit the focus list
  const int focus_period = control_.focus_sweeps + 1;
  const bool full =
      !focus_ || s == 0 ||
      ((s + 1 - control_.min_sweeps) % focus_period + focus_period) % focus_period == 0;
  const bool blocked = !joints_.empty() && !coloured_; // the full sweeps visit free_
  const int *list = full ? (blocked ? free_.data() : nullptr) : focus_contacts_.data();
  const int count = full ? (blocked ? static_cast<int>(free_.size()) : nc_)
                         : static_cast<int>(focus_contacts_.size());
  double *changes = full && focus_ ? contact_changes_.data() : nullptr;
  // Anderson: plain sweeps up to the floor (steps that it ends pay nothing), the history from
  // its last sweep on, a mix after every `period` sweeps
  const bool mixing = accelerate_ && !plain_ && s + 1 >= control_.min_sweeps;
  const bool mix = mixing && (s + 1 - control_.min_sweeps) % period_ == period_ - 1;
  if (mixing && !anderson_.has_start()) anderson_.start(lambda_);
  combination_ = false;
  std::vector<std::unique_ptr<GroupedSweep>> &grouped = *grouped_;
  if (coloured_) {
    for (std::size_t p = 0; p < phases_.size(); ++p) {
      if (p > 0) keep_start(); // the first phase starts where the sweep does
      sweep_and_sum(phases_[p].data(), static_cast<int>(phases_[p].size()),
                    grouped.empty() ? nullptr : grouped[p].get(),
                    joints_.empty() ? nullptr : &joints_[p], norms, changes);
    }
  } else {
    sweep_and_sum(list, count, grouped.empty() ? nullptr : grouped[0].get(),
                  blocked ? &joints_[0] : nullptr, norms, changes);
  }
  if (changes) focus_list(contact_changes_, norms[0], focus_contacts_);
  res_.visits += count;
  ex_.sum(norms, 3); // every process alike, with joints or without
  ++res_.sweeps;
  if (!std::isfinite(norms[0]) || !std::isfinite(norms[1])) {
    lambda_ = lambda_start_;
    if (accelerate_) // the checkpoint may be a combination outside the cones
      for (int c = 0; c < nc_; ++c) cones_.project(lambda_.data() + Eigen::Index(rows_) * c, c);
    res_.reason = StopReason::non_finite;
    return true;
  }
  res_.record(norms[1] > 0 ? std::sqrt(norms[0] / norms[1]) : 0.0, full);
  if (norms[2] > 0 && norms[1] > norms[2])
    res_.contact_scale = std::sqrt(norms[1] / (norms[1] - norms[2]));
  // lambda is this sweep's result (feasible); a new smallest change is kept now and then
  if (mixing && s % kCheckpointSweeps == 0 && res_.last_change < best_) {
    lambda_best_ = lambda_;
    have_best_ = true;
  }
  if (mix) {
    res_.singular_value = anderson_.mix(lambda_, dv_); // lambda: the next start
    res_.mixed_change = anderson_.change();
    combination_ = anderson_.combined();
  }
  if (stop_rule(full, norms) || stalled()) return true;
  if (full && slow()) {
    res_.slow_restarts = 1;
    return true;
  }
  if (control_.nonlinear_cg && s + 1 < control_.max_sweeps) cg_step(s, norms[0]);
  return false;
}

// Whether the sweeps are predicted to be slow enough to start again (PgsControl::restart_sweeps;
// global norms: every process alike).
bool PgsRun::slow() const
{
  if (!(control_.restart_sweeps > 0) || !accelerate_ || plain_ || !(control_.accuracy > 0) ||
      res_.sweeps < control_.probe_sweeps)
    return false;
  return res_.predicted_sweeps(control_.accuracy) > control_.restart_sweeps;
}

// The stop rule after a sweep; true where the sweeps have converged.
bool PgsRun::stop_rule(bool full, const double *norms)
{
  res_.reason = StopReason::max_iterations;
  // with a floor, a met estimate stops the sweeps at the floor: the changes of the sweeps after
  // it may fall to round-off, where the estimated rate means nothing
  if (control_.accuracy > 0 && !(res_.met_estimate <= control_.accuracy) &&
      res_.error_estimate() <= control_.accuracy)
    res_.met_estimate = res_.error_estimate();
  // A full sweep that moves lambda by round-off only has converged as far as doubles go: its
  // changes may then repeat exactly (a rate of 1, an infinite estimate; a solved column under
  // focused sweeps swept on into stagnation).
  constexpr double kRoundOff = 64 * std::numeric_limits<double>::epsilon();
  const bool still = full && res_.last_change <= kRoundOff; // 0 too: a sweep that changes nothing
  if (still && control_.accuracy > 0)
    res_.met_estimate = std::min(res_.met_estimate, res_.last_change);
  const bool done = control_.accuracy > 0 ? res_.met_estimate <= control_.accuracy &&
                                                (res_.sweeps >= control_.min_sweeps || still)
                                          : !(norms[0] > control_.tol * control_.tol * norms[1]);
  if (done && full) {
    res_.reason = StopReason::converged;
    return true;
  }
  return false;
}

// The stall rule after a sweep that did not converge; true where the sweeps end. Anderson's
// sweeps that stall go on plain from the best checkpoint.
bool PgsRun::stalled()
{
  const bool anderson_on = accelerate_ && !plain_;
  if (res_.last_change < best_) {
    best_ = res_.last_change;
    since_best_ = 0;
    return false;
  }
  if (++since_best_ <
      (anderson_on ? std::min(control_.stall_sweeps, kAndersonStallSweeps) : control_.stall_sweeps))
    return false;
  if (!anderson_on) {
    res_.reason = StopReason::stagnation;
    return true;
  }
  plain_ = true;
  anderson_.restart();
  res_.restart_rate(); // the estimate follows the plain sweeps' own contraction
  combination_ = false;
  if (have_best_) { // a collective: every process, with or without contacts
    lambda_ = lambda_best_;
    dv_ = velocity_change(sys_, ex_, lambda_);
  }
  best_ = INFINITY;
  since_best_ = 0;
  return false;
}

// Nonlinear CG's step along its direction after sweep s, whose change^2 is change2.
void PgsRun::cg_step(int s, double change2)
{
  change_ = lambda_ - lambda_start_;
  const double beta = s > 0 ? change2 / last_change2_ : 2.0;
  last_change2_ = change2;
  if (beta > 1.0) {
    direction_ = change_; // restart
  } else {
    direction_ *= beta;
    lambda_ += direction_;
    dv_ += velocity_change(sys_, ex_, direction_);
    direction_ += change_;
  }
}

} // namespace

PgsResult pgs(const ContactSystem &sys, const Exchange &ex, const Cones &cones, const Vector &b,
              const std::vector<Vec6> &scale, Vector &lambda, const PgsControl &control)
{
  PgsResult res = PgsRun(sys, ex, cones, b, scale, lambda, control).run();
  if (res.slow_restarts == 0 || res.sweeps >= control.max_sweeps) return res;
  PgsControl again = control;
  again.max_sweeps = control.max_sweeps - res.sweeps;
  again.restart_sweeps = 0;
  res.append(PgsRun(sys, ex, cones, b, scale, lambda, again).run());
  return res;
}

} // namespace fibre
