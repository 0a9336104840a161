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

// The body that holds a local body's velocity: itself, or an image's body (Exchange::local_owners).
int owner_of(const std::vector<int> &owners, int body)
{
  return owners.empty() ? body : owners[body];
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

// Anderson acceleration of the sweeps (PgsControl::anderson). The sweeps from the start x
// (PgsControl::anderson_period of them) give g = G(x) and f = g - x; with the differences dF,
// dG of the last `memory` pairs (f, g), the next start is g - dG gamma, gamma = argmin
// |f - dF gamma|. dv is linear in lambda, so the start's velocities combine the same way from
// the stored differences of the sweeps' dv. The Gram matrix dF^T dF and dF^T f are kept up to
// date with one new column a mix.
class Anderson {
 public:
  Anderson(int memory, const Exchange &ex) : memory_(memory), ex_(ex) {}

  // The start of the sweeps that the next mix combines (the mixes set it after the first).
  bool has_start() const { return has_start_; }
  void start(const Vector &lambda)
  {
    x_ = lambda;
    has_start_ = true;
  }

  // `lambda`, `dv` = g and its velocities; on return they hold the next start. Returns the
  // smallest ratio |dF_i| / |dX_i| over the history (dX the differences of the starts): near
  // the solution dF = (J - I) dX, so it estimates the smallest singular value of I - J, and
  // g's error is about |f| over it (infinite without a history: the next start is then g).
  double mix(Vector &lambda, Vector &dv)
  {
    const Eigen::Index n = lambda.size();
    const bool first = !started_;
    int j = -1; // the new column
    if (!first) {
      j = newest_ = (newest_ + 1) % memory_; // the oldest column gives way
      if (count_ < memory_) {
        ++count_;
        dF_.resize(count_), dG_.resize(count_), dDV_.resize(count_), dX2_.resize(count_);
      }
      dF_[j].resize(n), dG_[j].resize(n);
    } else { // the first mix, or after a restart (every process alike: a process without
             // contacts takes part in the sums below)
      started_ = true;
      f_prev_.resize(n);
      g_prev_.resize(n);
    }
    // One pass in blocks that stay in cache: f = g - x, and after the first mix the new
    // columns dF_j, dG_j, then dF_j . f_prev, |dX_j|^2 (dX = dG - dF) and the Gram matrix's new
    // column dF_i . dF_j; |f|^2 and |g|^2 always. The dot products and the copies are Eigen's
    // (vectorized, several accumulators): a plain loop's single running sum is a chain of
    // dependent adds, and its possible aliasing kept it scalar.
    std::vector<double> &dots = dots_;
    dots.assign(count_ + 4, 0.0);
    double *f2 = &dots[count_ + 2], *g2 = &dots[count_ + 3];
    columns(dF_);
    double *fp = f_prev_.data(), *gp = g_prev_.data();
    const double *l = lambda.data(), *x = x_.data();
    for (Eigen::Index e0 = 0; e0 < n; e0 += kBlock) {
      const Eigen::Index len = std::min(n - e0, kBlock);
      const ConstMap l_block(l + e0, len);
      Map f_block(f_.data(), len);
      f_block = l_block - ConstMap(x + e0, len);
      *f2 += f_block.squaredNorm();
      *g2 += l_block.squaredNorm();
      if (!first) {
        double *df = dF_[j].data(), *dg = dG_[j].data();
        Map(df + e0, len) = f_block - ConstMap(fp + e0, len);
        Map(dg + e0, len) = l_block - ConstMap(gp + e0, len);
        const ConstMap df_block(df + e0, len), dg_block(dg + e0, len);
        dots[count_] += df_block.dot(ConstMap(fp + e0, len));
        dots[count_ + 1] += (dg_block - df_block).squaredNorm();
        for (int i = 0; i < count_; ++i) dots[i] += ConstMap(ptr_[i] + e0, len).dot(df_block);
      }
      Map(fp + e0, len) = f_block;
      Map(gp + e0, len) = l_block;
    }
    ex_.sum(dots.data(), count_ + 4);
    // A mix whose change exceeds the last one's crossed a kink of the cones (the sliding or
    // open set changed): the old differences describe another map, and kept they stall the
    // combination (measured: changes stuck at 1e-5 on a forming stiff pile). The history
    // starts again from this mix.
    const double change = *g2 > 0 ? std::sqrt(*f2 / *g2) : 0.0;
    const bool grew = change > change_;
    change_ = change;
    combined_ = false;
    if (first || grew) {
      count_ = 0;
      newest_ = -1;
      dv_prev_ = dv;
      x_ = lambda; // the next start is g
      return sigma_;
    }
    // rhs_i = dF_i . f with f = f_prev + dF_j
    for (int i = 0; i < count_; ++i) {
      gram_(i, j) = gram_(j, i) = dots[i];
      rhs_[i] = i == j ? dots[count_] + dots[j] : rhs_[i] + dots[i];
    }
    dX2_[j] = dots[count_ + 1];
    for (int i = 0; i < count_; ++i)
      if (dX2_[i] > 0) sigma_ = std::min(sigma_, std::sqrt(gram_(i, i) / dX2_[i]));
    // a small Tikhonov term keeps nearly parallel columns from amplifying round-off
    const Eigen::MatrixXd h = gram_.topLeftCorner(count_, count_);
    const double shift = 1e-10 * h.trace() / count_;
    const Vector gamma =
        (h + shift * Eigen::MatrixXd::Identity(count_, count_)).ldlt().solve(rhs_.head(count_));
    combined_ = gamma.allFinite();
    if (!combined_) {
      restart();
      x_ = lambda;
      return sigma_;
    }
    // the velocities' new column dv - dv_prev in the same pass as their combination
    dDV_[j].resize(dv.size());
    combine(dDV_, gamma, dv, dv_prev_.data(), dDV_[j].data());
    combine(dG_, gamma, lambda, nullptr, nullptr, x_.data());
    return sigma_;
  }

  // Whether the last mix combined: lambda is then not the last sweep's impulses.
  bool combined() const { return combined_; }
  // The last mix's g (the sweeps' impulses, feasible) and its |f| / |g|.
  const Vector &sweep_result() const { return g_prev_; }
  double change() const { return change_; }

  // Forget the history (the next mix starts a new one; the start stays).
  void restart()
  {
    count_ = 0;
    newest_ = -1;
    started_ = false;
    combined_ = false;
  }

 private:
  // the columns' data in ptr_
  void columns(const std::vector<Vector> &v)
  {
    ptr_.resize(count_);
    for (int i = 0; i < count_; ++i) ptr_[i] = v[i].data();
  }
  // y -= sum_i gamma_i v_i in one pass; with `previous`, first the newest column
  // v_newest = y - previous and previous = y; with `copy`, copy = the result
  void combine(const std::vector<Vector> &v, const Vector &gamma, Vector &y, double *previous,
               double *newest, double *copy = nullptr)
  {
    columns(v);
    double *out = y.data();
    const Eigen::Index n = y.size();
    for (Eigen::Index e0 = 0; e0 < n; e0 += kBlock) { // a block of y stays in cache
      const Eigen::Index e1 = std::min(n, e0 + kBlock);
      if (previous)
        for (Eigen::Index e = e0; e < e1; ++e) {
          newest[e] = out[e] - previous[e];
          previous[e] = out[e];
        }
      for (int i = 0; i < count_; ++i) {
        const double *p = ptr_[i], gi = gamma[i];
        for (Eigen::Index e = e0; e < e1; ++e) out[e] -= gi * p[e];
      }
      if (copy) std::copy(out + e0, out + e1, copy + e0);
    }
  }

  using Map = Eigen::Map<Vector>;
  using ConstMap = Eigen::Map<const Vector>;
  static constexpr Eigen::Index kBlock = 512;
  int memory_;
  const Exchange &ex_;
  std::vector<const double *> ptr_;
  int count_ = 0, newest_ = -1;
  double sigma_ = INFINITY;  // the smallest over the whole solve: restarts keep it
  double change_ = INFINITY; // the last mix's |f| / |g|
  bool combined_ = false, started_ = false, has_start_ = false;
  std::vector<Vector> dF_, dG_, dDV_;
  std::vector<double> dX2_, dots_;
  Vector x_, f_prev_, g_prev_, dv_prev_;
  Vector f_ = Vector(kBlock);
  Eigen::MatrixXd gram_ = Eigen::MatrixXd::Zero(memory_, memory_);
  Vector rhs_ = Vector::Zero(memory_);
};

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

} // namespace

PgsResult pgs(const ContactSystem &sys, const Exchange &ex, const Cones &cones, const Vector &b,
              const std::vector<Vec6> &scale, Vector &lambda, const PgsControl &control)
{
  PgsResult res;
  const int nc = sys.num_contacts(), rows = sys.rows();
  const bool halo = ex.has_halo(); // else the round trip below is the identity
  const std::vector<char> touched = halo ? touched_bodies(sys, ex) : std::vector<char>();
  // the blocks' corrections are not part of the sweeps' steps, and measured with them the
  // combination diverged on a stiff pile: plain sweeps only
  const bool accelerate = control.anderson > 0 && !control.nonlinear_cg && !control.fibre_blocks;
  const bool focus =
      control.focus_sweeps > 0 && !control.nonlinear_cg && !control.fibre_blocks && !accelerate;
  // Two process colours (Exchange::Halo::colours): the contacts on bodies that other
  // processes' contacts move too are swept in their process's colour's phase of the sweep, so
  // that a body that processes of two colours share moves as on one process. A body that
  // processes of one colour share (all of them without colours) is split among them: each sees
  // a copy of inverse mass split / m (mass splitting). Neither with fibre blocks, whose
  // corrections move their bodies at their own mass, nor with nonlinear CG, whose steps along
  // its direction the split slowed (12 of test_fix_solvers' 60 steps at np 2 unconverged);
  // focused sweeps split only.
  const bool shareable = halo && !control.fibre_blocks && !control.nonlinear_cg;
  const bool colouring = shareable && !focus;
  const std::unique_ptr<Exchange::Halo> copies = halo ? ex.halo(touched, colouring) : nullptr;
  // (the counts per colour travel in a body's kBodyDofs entries)
  const int colours = colouring && copies->colours() <= kBodyDofs ? copies->colours() : 1;
  const int colour = colours > 1 ? copies->colour() : 0;
  const BodyShares shares = shareable ? body_shares(touched, ex, colours, colour) : BodyShares();
  const Vector &split = shares.split;
  std::vector<std::vector<int>> phases;
  if (colours > 1 && shares.total.size())
    phases = colour_phases(sys, ex, shares.total, colours, colour);
  const bool coloured = !phases.empty();
  Vector split_inv_mass;
  std::vector<Vec6> inv_scale(scale.size());
  if (split.size()) {
    split_inv_mass = sys.inv_mass().cwiseProduct(split);
    const std::vector<int> &owners = ex.local_owners();
    const auto split_of = [&](int body) {
      if (body < 0) return 1.0;
      return split[Eigen::Index(kBodyDofs) * owner_of(owners, body)];
    };
    std::vector<Vec6> diagonal(nc);
    for (int c = 0; c < nc; ++c) {
      const Contact &k = sys.contacts()[c];
      diagonal[c] = diagonal_entries(sys, c, split_of(k.a), split_of(k.b));
    }
    const std::vector<Vec6> split_scale = row_scales(diagonal, rows);
    for (int c = 0; c < nc; ++c) inv_scale[c] = split_scale[c].cwiseInverse();
  } else {
    for (std::size_t c = 0; c < scale.size(); ++c) inv_scale[c] = scale[c].cwiseInverse();
  }
  const double *inv_mass = split.size() ? split_inv_mass.data() : sys.inv_mass().data();
  // the blocks read their bound rows from feasible impulses
  if (control.fibre_blocks)
    for (int c = 0; c < nc; ++c) cones.project(lambda.data() + Eigen::Index(rows) * c, c);
  Vector dv = velocity_change(sys, ex, lambda);
  // Each phase's changes go to the other processes as `moved`, from dv_start, its start: on the
  // halo's bodies only where it names them (a few dozen, where a full vector has every ghost).
  const std::vector<int> *halo_bodies = halo ? copies->bodies() : nullptr;
  Vector dv_start = halo ? dv : Vector(), moved = halo ? Vector::Zero(dv.size()) : Vector();
  const auto keep_start = [&] {
    if (!halo_bodies) {
      dv_start = dv;
      return;
    }
    for (const int body : *halo_bodies) body_entries(dv_start, body) = body_entries(dv, body);
  };
  // Impulses to fall back on when a sweep turns non-finite: a copy every kCheckpointSweeps
  // sweeps, not every sweep (stiff steps take hundreds), and every sweep for nonlinear CG,
  // whose direction is the sweep's change.
  constexpr int kCheckpointSweeps = 16;
  Vector lambda_start;
  double best = INFINITY;
  int since_best = 0;
  // Anderson's combination can cycle where plain sweeps converge (a LIGGGHTS heap's step: its
  // rotations drifted off again after sweep 900). After kAndersonStallSweeps sweeps without a new
  // smallest change the sweeps go on plain from the best checkpointed sweep.
  bool plain = false, have_best = false; // have_best: alike on every process
  Vector lambda_best;
  Vector direction, change; // nonlinear CG
  double last_change2 = 0;
  std::unique_ptr<FibreBlocks> blocks;
  if (control.fibre_blocks) {
    Vector normal(nc);
    for (int c = 0; c < nc; ++c) normal[c] = lambda[Eigen::Index(rows) * c];
    blocks =
        std::make_unique<FibreBlocks>(sys, ex.local_owners(), cones, control.block_weight, &normal);
  }
  // Four contacts at a time where the processor can (sweep_groups.hpp): the full sweeps, or
  // each colour phase; not the focused sweeps' lists
  // (kept in control.cache while the kinematics hold: the same contacts, phases and masses)
  std::vector<std::unique_ptr<GroupedSweep>> own;
  std::vector<std::unique_ptr<GroupedSweep>> &grouped =
      control.cache ? control.cache->grouped : own;
  if (control.grouped && !focus && grouped_sweeps_available()) {
    const std::size_t wanted = coloured ? phases.size() : 1;
    const bool kept = control.cache && control.cache->kinematics == sys.kinematics_id() &&
                      control.cache->split_masses == (split.size() > 0) &&
                      grouped.size() == wanted && sys.row_mask().empty();
    if (kept) {
      for (const std::unique_ptr<GroupedSweep> &group : grouped)
        group->refresh(sys, cones, b, inv_scale);
    } else {
      grouped.clear();
      if (coloured)
        for (const std::vector<int> &phase : phases)
          grouped.push_back(std::make_unique<GroupedSweep>(sys, cones, b, inv_mass, inv_scale,
                                                           ex.local_owners(), &phase));
      else
        grouped.push_back(
            std::make_unique<GroupedSweep>(sys, cones, b, inv_mass, inv_scale, ex.local_owners()));
      if (control.cache) {
        control.cache->kinematics = sys.row_mask().empty() ? sys.kinematics_id() : 0;
        control.cache->split_masses = split.size() > 0;
      }
    }
  } else {
    grouped.clear();
    if (control.cache) control.cache->kinematics = 0;
  }
  Anderson anderson(std::max(control.anderson, 1), ex);
  const int period = std::max(control.anderson_period, 1);
  bool combination = false; // lambda is Anderson's start, not a sweep's result
  std::vector<double> contact_changes(focus ? nc : 0);
  std::vector<int> focus_contacts;
  for (int s = 0; s < control.max_sweeps; ++s) {
    // dv follows this process's updates; `moved` collects them for the other processes.
    if (halo) keep_start();
    if (control.nonlinear_cg || s % kCheckpointSweeps == 0) lambda_start = lambda;
    if (blocks) blocks->correct(b, lambda, dv);
    double norms[2] = {0, 0}; // ||change||^2, ||lambda||^2
    // focused: the first sweep is full, then every (P + 1)-th counted from min_sweeps (so the
    // rules can stop where plain sweeps would); the P between visit the focus list
    const int focus_period = control.focus_sweeps + 1;
    const bool full =
        !focus || s == 0 ||
        ((s + 1 - control.min_sweeps) % focus_period + focus_period) % focus_period == 0;
    const int *list = full ? nullptr : focus_contacts.data();
    const int count = full ? nc : static_cast<int>(focus_contacts.size());
    double *changes = full && focus ? contact_changes.data() : nullptr;
    // Anderson: plain sweeps up to the floor (steps that it ends pay nothing), the history
    // from its last sweep on, a mix after every `period` sweeps
    const bool mixing = accelerate && !plain && s + 1 >= control.min_sweeps;
    const bool mix = mixing && (s + 1 - control.min_sweeps) % period == period - 1;
    if (mixing && !anderson.has_start()) anderson.start(lambda);
    combination = false;
    // Every process's updates on every body: the sum of the local changes, owners and ghosts
    // (each copy's change at the body's own mass); with colours after each colour's phase.
    const auto sweep_and_sum = [&](const int *visit, int n, GroupedSweep *group) {
      if (group) {
        group->sweep(lambda, dv, norms);
        visit = group->singles().data(); // then the rest one at a time
        n = static_cast<int>(group->singles().size());
      }
      if (rows == 6)
        sweep<6>(sys, cones, b, inv_mass, inv_scale, ex.local_owners(), visit, n, lambda, dv, norms,
                 changes);
      else
        sweep<3>(sys, cones, b, inv_mass, inv_scale, ex.local_owners(), visit, n, lambda, dv, norms,
                 changes);
      if (halo) {
        if (!halo_bodies) {
          moved = dv - dv_start;
          if (split.size()) moved.array() /= split.array();
          copies->sum_copies(moved);
          dv = dv_start + moved;
          return;
        }
        for (const int body : *halo_bodies) {
          body_entries(moved, body) = body_entries(dv, body) - body_entries(dv_start, body);
          if (split.size()) body_entries(moved, body).array() /= body_entries(split, body).array();
        }
        copies->sum_copies(moved);
        for (const int body : *halo_bodies)
          body_entries(dv, body) = body_entries(dv_start, body) + body_entries(moved, body);
      }
    };
    if (coloured) {
      for (std::size_t p = 0; p < phases.size(); ++p) {
        if (p > 0) keep_start(); // the first phase starts where the sweep does
        sweep_and_sum(phases[p].data(), static_cast<int>(phases[p].size()),
                      grouped.empty() ? nullptr : grouped[p].get());
      }
    } else {
      sweep_and_sum(list, count, grouped.empty() ? nullptr : grouped[0].get()); // no list then
    }
    if (changes) focus_list(contact_changes, norms[0], focus_contacts);
    res.visits += count;
    ex.sum(norms, 2);
    ++res.sweeps;
    if (!std::isfinite(norms[0]) || !std::isfinite(norms[1])) {
      lambda = lambda_start;
      if (accelerate) // the checkpoint may be a combination outside the cones
        for (int c = 0; c < nc; ++c) cones.project(lambda.data() + Eigen::Index(rows) * c, c);
      res.reason = StopReason::non_finite;
      return res;
    }
    res.record(norms[1] > 0 ? std::sqrt(norms[0] / norms[1]) : 0.0, full);
    // lambda is this sweep's result (feasible); a new smallest change is kept now and then
    if (mixing && s % kCheckpointSweeps == 0 && res.last_change < best) {
      lambda_best = lambda;
      have_best = true;
    }
    if (mix) {
      res.singular_value = anderson.mix(lambda, dv); // lambda: the next start
      res.mixed_change = anderson.change();
      combination = anderson.combined();
    }
    res.reason = StopReason::max_iterations;
    // with a floor, a met estimate stops the sweeps at the floor: the changes of the sweeps
    // after it may fall to round-off, where the estimated rate means nothing
    if (control.accuracy > 0 && !(res.met_estimate <= control.accuracy) &&
        res.error_estimate() <= control.accuracy)
      res.met_estimate = res.error_estimate();
    // A full sweep that moves lambda by round-off only has converged as far as doubles go: its
    // changes may then repeat exactly (a rate of 1, an infinite estimate; a solved column under
    // focused sweeps swept on into stagnation).
    constexpr double kRoundOff = 64 * std::numeric_limits<double>::epsilon();
    const bool still = full && res.last_change <= kRoundOff; // 0 too: a sweep that changes nothing
    if (still && control.accuracy > 0)
      res.met_estimate = std::min(res.met_estimate, res.last_change);
    const bool done = control.accuracy > 0 ? res.met_estimate <= control.accuracy &&
                                                 (res.sweeps >= control.min_sweeps || still)
                                           : !(norms[0] > control.tol * control.tol * norms[1]);
    if (done && full) {
      res.reason = StopReason::converged;
      break;
    }
    const bool anderson_on = accelerate && !plain;
    if (res.last_change < best) {
      best = res.last_change;
      since_best = 0;
    } else if (++since_best >= (anderson_on ? std::min(control.stall_sweeps, kAndersonStallSweeps)
                                            : control.stall_sweeps)) {
      if (!anderson_on) {
        res.reason = StopReason::stagnation;
        break;
      }
      plain = true;
      anderson.restart();
      res.restart_rate(); // the estimate follows the plain sweeps' own contraction
      combination = false;
      if (have_best) { // a collective: every process, with or without contacts
        lambda = lambda_best;
        dv = velocity_change(sys, ex, lambda);
      }
      best = INFINITY;
      since_best = 0;
    }
    if (control.nonlinear_cg && s + 1 < control.max_sweeps) {
      change = lambda - lambda_start;
      const double beta = s > 0 ? norms[0] / last_change2 : 2.0;
      last_change2 = norms[0];
      if (beta > 1.0) {
        direction = change; // restart
      } else {
        direction *= beta;
        lambda += direction;
        dv += velocity_change(sys, ex, direction);
        direction += change;
      }
    }
  }
  if (combination) lambda = anderson.sweep_result();
  if (control.nonlinear_cg) // the last step along the direction may have left the cones
    for (int c = 0; c < nc; ++c) cones.project(lambda.data() + Eigen::Index(rows) * c, c);
  return res;
}

} // namespace fibre
