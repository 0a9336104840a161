#include "fibre/solvers/sweep_groups.hpp"

#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "fibre/core/exchange.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#define FIBRE_GROUPED_SWEEPS 1
#include <immintrin.h>
#endif

namespace fibre {

ContactGroups group_contacts(const ContactSystem &sys, const std::vector<int> &owners,
                             const std::vector<int> *list)
{
  constexpr int kOpen = 16; // open groups at most: a bit each in a body's mask
  const int nc = sys.num_contacts();
  const int *pairs = sys.body_pairs();
  const auto owner = [&](int body) { return owner_of(owners, body); };
  std::vector<std::uint32_t> holding(sys.num_bodies(), 0); // per body: the open groups with it
  std::array<ContactGroup, kOpen> open{};
  std::array<int, kOpen> filled{}, opened{};
  std::uint32_t used = 0;
  int clock = 0;
  ContactGroups out;
  const auto oldest_of = [&](std::uint32_t set) {
    int oldest = -1;
    for (std::uint32_t s = set; s; s &= s - 1) {
      const int k = __builtin_ctz(s);
      if (oldest < 0 || opened[k] < opened[oldest]) oldest = k;
    }
    return oldest;
  };
  const auto close = [&](int slot) {
    out.groups.push_back(open[slot]);
    for (int j = 0; j < filled[slot]; ++j) {
      const int c = open[slot][j];
      holding[owner(pairs[2 * c])] &= ~(1u << slot);
      if (pairs[2 * c + 1] >= 0) holding[owner(pairs[2 * c + 1])] &= ~(1u << slot);
    }
    used &= ~(1u << slot);
  };
  const int count = list ? static_cast<int>(list->size()) : nc;
  for (int k = 0; k < count; ++k) {
    const int c = list ? (*list)[k] : k;
    const int a = owner(pairs[2 * c]), b = owner(pairs[2 * c + 1]);
    if (a == b) {
      out.singles.push_back(c);
      continue;
    }
    int slot = oldest_of(used & ~holding[a] & ~(b >= 0 ? holding[b] : 0u));
    if (slot < 0) {
      if (used == (1u << kOpen) - 1) close(oldest_of(used));
      slot = __builtin_ctz(~used);
      used |= 1u << slot;
      filled[slot] = 0;
      opened[slot] = clock++;
      open[slot].fill(-1);
    }
    open[slot][filled[slot]++] = c;
    holding[a] |= 1u << slot;
    if (b >= 0) holding[b] |= 1u << slot;
    if (filled[slot] == kGroupLanes) close(slot);
  }
  while (used) close(oldest_of(used));
  return out;
}

namespace {

// The packed fields of a group, kGroupLanes numbers each.
enum : int {
  kFrame = 0, // D (9, column-major, rows n t1 t2), ra (3), rb (3): ContactKinematics
  kRhs = 15,  // b, Sigma and 1 / scale: 6 rows each (3 used with rows 3)
  kSigma = 21,
  kScale = 27,
  kMassA = 33, // the bodies' inverse mass and inertia (zero for a wall's side and an empty
  kMassB = 35, // lane): a sphere's three of each are one number
  kCoeff = 37, // the cones' coefficients
  kPull = 40,  // h times the pull-off force (Cones::pull)
  kFields = 41
};

// A body's three inverse masses (or inertias), which the groups pack as one.
double isotropic(const double *m)
{
  if ((m[1] != m[0] || m[2] != m[0]) && !std::isnan(m[0]))
    throw std::logic_error("GroupedSweep: a body's inverse masses differ by axis");
  return m[0];
}

} // namespace

GroupedSweep::GroupedSweep(const ContactSystem &sys, const Cones &cones, const Vector &b,
                           const double *inv_mass, const std::vector<Vec6> &inv_scale,
                           const std::vector<int> &owners, const std::vector<int> *list)
    : rows_(sys.rows())
{
  ContactGroups grouped = group_contacts(sys, owners, list);
  singles_ = std::move(grouped.singles);
  const std::size_t lanes = grouped.groups.size() * kGroupLanes;
  contact_.assign(lanes, -1);
  body_a_.assign(lanes, -1);
  body_b_.assign(lanes, -1);
  pack_.assign(grouped.groups.size() * kFields * kGroupLanes, 0.0);
  const int *pairs = sys.body_pairs();
  const auto owner = [&](int body) { return owner_of(owners, body); };
  for (std::size_t lane = 0; lane < lanes; ++lane) {
    const int c = grouped.groups[lane / kGroupLanes][lane % kGroupLanes];
    if (c < 0) continue;
    contact_[lane] = c;
    const int a = owner(pairs[2 * c]), bb = owner(pairs[2 * c + 1]);
    body_a_[lane] = a;
    body_b_[lane] = bb;
    double *p = pack_.data() + (lane / kGroupLanes) * kFields * kGroupLanes + lane % kGroupLanes;
    const auto put = [p](int field, double value) { p[kGroupLanes * field] = value; };
    const double *q = sys.kinematics(c).frame.data();
    for (int f = 0; f < 15; ++f) put(kFrame + f, q[f]);
    for (int d = 0; d < 2; ++d) {
      put(kMassA + d, isotropic(inv_mass + 6 * std::size_t(a) + 3 * d));
      put(kMassB + d, bb >= 0 ? isotropic(inv_mass + 6 * std::size_t(bb) + 3 * d) : 0.0);
    }
  }
  refresh(sys, cones, b, inv_scale);
}

void GroupedSweep::refresh(const ContactSystem &sys, const Cones &cones, const Vector &b,
                           const std::vector<Vec6> &inv_scale)
{
  const double *sigma = sys.sigma().data();
  const std::size_t R = std::size_t(rows_);
  cohesive_ = cones.cohesive();
  for (std::size_t lane = 0; lane < contact_.size(); ++lane) {
    const int c = contact_[lane];
    if (c < 0) continue;
    double *p = pack_.data() + (lane / kGroupLanes) * kFields * kGroupLanes + lane % kGroupLanes;
    const auto put = [p](int field, double value) { p[kGroupLanes * field] = value; };
    for (std::size_t i = 0; i < R; ++i) {
      put(kRhs + int(i), b[Eigen::Index(R * c + i)]);
      put(kSigma + int(i), sigma[R * c + i]);
      put(kScale + int(i), inv_scale[c][Eigen::Index(i)]);
    }
    for (int k = 0; k < num_cones(rows_); ++k) put(kCoeff + k, cones.coeff(c, k));
    put(kPull, cones.pull(c));
  }
}

#ifdef FIBRE_GROUPED_SWEEPS

bool grouped_sweeps_available()
{
  static const bool ok = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return ok;
}

namespace {

#define FIBRE_AVX2 __attribute__((target("avx2,fma"), always_inline)) inline

// v[d] = (p[0][d], .., p[3][d]) for d < 6: a 4 x 4 transpose and two pairs.
FIBRE_AVX2 void load_lanes6(double *const p[4], __m256d v[6])
{
  const __m256d r0 = _mm256_loadu_pd(p[0]), r1 = _mm256_loadu_pd(p[1]), r2 = _mm256_loadu_pd(p[2]),
                r3 = _mm256_loadu_pd(p[3]);
  const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1),
                t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
  v[0] = _mm256_permute2f128_pd(t0, t2, 0x20);
  v[1] = _mm256_permute2f128_pd(t1, t3, 0x20);
  v[2] = _mm256_permute2f128_pd(t0, t2, 0x31);
  v[3] = _mm256_permute2f128_pd(t1, t3, 0x31);
  const __m256d a = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p[0] + 4)),
                                         _mm_loadu_pd(p[2] + 4), 1);
  const __m256d b = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(p[1] + 4)),
                                         _mm_loadu_pd(p[3] + 4), 1);
  v[4] = _mm256_unpacklo_pd(a, b);
  v[5] = _mm256_unpackhi_pd(a, b);
}

// The inverse: p[j][d] = v[d] lane j, d < 6.
FIBRE_AVX2 void store_lanes6(double *const p[4], const __m256d v[6])
{
  const __m256d t0 = _mm256_unpacklo_pd(v[0], v[1]), t1 = _mm256_unpackhi_pd(v[0], v[1]),
                t2 = _mm256_unpacklo_pd(v[2], v[3]), t3 = _mm256_unpackhi_pd(v[2], v[3]);
  _mm256_storeu_pd(p[0], _mm256_permute2f128_pd(t0, t2, 0x20));
  _mm256_storeu_pd(p[1], _mm256_permute2f128_pd(t1, t3, 0x20));
  _mm256_storeu_pd(p[2], _mm256_permute2f128_pd(t0, t2, 0x31));
  _mm256_storeu_pd(p[3], _mm256_permute2f128_pd(t1, t3, 0x31));
  const __m256d a = _mm256_unpacklo_pd(v[4], v[5]), b = _mm256_unpackhi_pd(v[4], v[5]);
  _mm_storeu_pd(p[0] + 4, _mm256_castpd256_pd128(a));
  _mm_storeu_pd(p[2] + 4, _mm256_extractf128_pd(a, 1));
  _mm_storeu_pd(p[1] + 4, _mm256_castpd256_pd128(b));
  _mm_storeu_pd(p[3] + 4, _mm256_extractf128_pd(b, 1));
}

// Rows 3: one number at a time (a vector load would read past the last contact).
FIBRE_AVX2 void load_lanes3(double *const p[4], __m256d v[3])
{
  for (int i = 0; i < 3; ++i) v[i] = _mm256_set_pd(p[3][i], p[2][i], p[1][i], p[0][i]);
}
FIBRE_AVX2 void store_lanes3(double *const p[4], const __m256d v[3])
{
  alignas(32) double out[3][4];
  for (int i = 0; i < 3; ++i) _mm256_store_pd(out[i], v[i]);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 3; ++i) p[j][i] = out[i][j];
}

template <int R> FIBRE_AVX2 void load_rows(double *const p[4], __m256d *v)
{
  if constexpr (R == 6)
    load_lanes6(p, v);
  else
    load_lanes3(p, v);
}
template <int R> FIBRE_AVX2 void store_rows(double *const p[4], const __m256d *v)
{
  if constexpr (R == 6)
    store_lanes6(p, v);
  else
    store_lanes3(p, v);
}

// t = v + omega x r: the velocity of a body's point at lever r (w: the body's six velocities).
FIBRE_AVX2 void point_velocity(const __m256d w[6], const __m256d r[3], __m256d t[3])
{
  t[0] = _mm256_fmsub_pd(w[4], r[2], _mm256_fmsub_pd(w[5], r[1], w[0]));
  t[1] = _mm256_fmsub_pd(w[5], r[0], _mm256_fmsub_pd(w[3], r[2], w[1]));
  t[2] = _mm256_fmsub_pd(w[3], r[1], _mm256_fmsub_pd(w[4], r[0], w[2]));
}

// y = [f; r x f + m]: an impulse f and moment m at lever r on a body (contact_impulse).
FIBRE_AVX2 void body_impulse(const __m256d r[3], const __m256d f[3], const __m256d m[3],
                             __m256d y[6])
{
  y[0] = f[0];
  y[1] = f[1];
  y[2] = f[2];
  y[3] = _mm256_add_pd(_mm256_fmsub_pd(r[1], f[2], _mm256_mul_pd(r[2], f[1])), m[0]);
  y[4] = _mm256_add_pd(_mm256_fmsub_pd(r[2], f[0], _mm256_mul_pd(r[0], f[2])), m[1]);
  y[5] = _mm256_add_pd(_mm256_fmsub_pd(r[0], f[1], _mm256_mul_pd(r[1], f[0])), m[2]);
}

// u = D t: a velocity t in the contact's frame (D's rows n, t1, t2).
FIBRE_AVX2 void frame_rows(const __m256d D[9], __m256d t0, __m256d t1, __m256d t2, __m256d u[3])
{
  for (int i = 0; i < 3; ++i)
    u[i] = _mm256_fmadd_pd(D[i + 6], t2, _mm256_fmadd_pd(D[i + 3], t1, _mm256_mul_pd(D[i], t0)));
}

// lambda_n >= 0 (NaN and infinity to 0), then each cone (Cones::project_rows) of four
// contacts' rows x, whose packed data starts at p. Cohesive (C): lambda_n >= -h pull (NaN to
// the bound, infinity to 0), and the cones' load lambda_n + 2 h pull.
template <int R, bool C> FIBRE_AVX2 void project_lanes(const double *p, __m256d x[R])
{
  using V = __m256d;
  const V zero = _mm256_setzero_pd(), inf = _mm256_set1_pd(INFINITY), one = _mm256_set1_pd(1.0);
  V load;
  if constexpr (C) {
    const V pull = _mm256_loadu_pd(p + kGroupLanes * kPull), lo = _mm256_sub_pd(zero, pull);
    x[0] = _mm256_blendv_pd(lo, x[0], _mm256_cmp_pd(x[0], lo, _CMP_GT_OQ));
    x[0] = _mm256_and_pd(_mm256_cmp_pd(x[0], inf, _CMP_LT_OQ), x[0]);
    load = _mm256_add_pd(x[0], _mm256_add_pd(pull, pull));
  } else {
    x[0] = _mm256_and_pd(
        _mm256_and_pd(_mm256_cmp_pd(x[0], zero, _CMP_GT_OQ), _mm256_cmp_pd(x[0], inf, _CMP_LT_OQ)),
        x[0]);
    load = x[0];
  }
  for (int k = 0; k < num_cones(R); ++k) {
    const int first = kCones[k].first;
    const bool pair = kCones[k].size == 2;
    const V radius = _mm256_mul_pd(_mm256_loadu_pd(p + kGroupLanes * (kCoeff + k)), load);
    V tn2 = _mm256_mul_pd(x[first], x[first]);
    if (pair) tn2 = _mm256_fmadd_pd(x[first + 1], x[first + 1], tn2);
    // inside: unchanged; outside: shrunk onto the cone; no cone or a non-finite norm: zero
    const V keep =
        _mm256_and_pd(_mm256_cmp_pd(radius, zero, _CMP_GT_OQ), _mm256_cmp_pd(tn2, inf, _CMP_LT_OQ));
    const V outside = _mm256_cmp_pd(tn2, _mm256_mul_pd(radius, radius), _CMP_GT_OQ);
    const V shrink = _mm256_blendv_pd(one, _mm256_div_pd(radius, _mm256_sqrt_pd(tn2)), outside);
    x[first] = _mm256_and_pd(keep, _mm256_mul_pd(x[first], shrink));
    if (pair) x[first + 1] = _mm256_and_pd(keep, _mm256_mul_pd(x[first + 1], shrink));
  }
}

// The bodies' velocities after a change delta of four contacts' rows: G^T delta
// (contact_impulse), f = D^T delta_t, m = D^T delta_r, y_a = [f; ra x f + m], y_b = -[f; rb x f +
// m]; then w += M^-1 y.
template <int R>
FIBRE_AVX2 void add_change(const double *p, const __m256d D[9], const __m256d ra[3],
                           const __m256d rb[3], const __m256d delta[R], __m256d va[6],
                           __m256d vb[6])
{
  using V = __m256d;
  const V zero = _mm256_setzero_pd();
  V f[3], m[3] = {zero, zero, zero};
  for (int k = 0; k < 3; ++k) {
    f[k] =
        _mm256_fmadd_pd(D[3 * k + 2], delta[2],
                        _mm256_fmadd_pd(D[3 * k + 1], delta[1], _mm256_mul_pd(D[3 * k], delta[0])));
    if constexpr (R == 6)
      m[k] = _mm256_fmadd_pd(
          D[3 * k + 2], delta[5],
          _mm256_fmadd_pd(D[3 * k + 1], delta[4], _mm256_mul_pd(D[3 * k], delta[3])));
  }
  V ya[6], yb[6];
  body_impulse(ra, f, m, ya);
  body_impulse(rb, f, m, yb);
  for (int d = 0; d < 6; ++d) {
    va[d] = _mm256_fmadd_pd(_mm256_loadu_pd(p + kGroupLanes * (kMassA + d / 3)), ya[d], va[d]);
    vb[d] = _mm256_fnmadd_pd(_mm256_loadu_pd(p + kGroupLanes * (kMassB + d / 3)), yb[d], vb[d]);
  }
}

// The sweep over the groups (pgs.cpp's sweep<R>, four contacts a step). An empty lane reads
// and writes zeros in `spare` (its packed data is zero); a wall's side reads and writes the
// spare body (its inverse mass is zero).
template <int R, bool C>
__attribute__((target("avx2,fma"))) void
sweep_groups(const double *pack, const int *contact, const int *body_a, const int *body_b,
             int groups, double *l, double *w, double norms[2])
{
  using V = __m256d;
  alignas(32) double spare_body[6] = {0, 0, 0, 0, 0, 0}, spare_rows[6] = {0, 0, 0, 0, 0, 0};
  const V zero = _mm256_setzero_pd();
  V change2 = zero, size2 = zero;
  for (int g = 0; g < groups; ++g) {
    const double *p = pack + std::size_t(g) * kFields * kGroupLanes;
#define FIBRE_FIELD(f) _mm256_loadu_pd(p + kGroupLanes * (f))
    double *wa[4], *wb[4], *lc[4];
    for (int j = 0; j < 4; ++j) {
      const std::size_t lane = std::size_t(g) * kGroupLanes + j;
      const int c = contact[lane];
      wa[j] = c >= 0 ? w + 6 * std::size_t(body_a[lane]) : spare_body;
      wb[j] = c >= 0 && body_b[lane] >= 0 ? w + 6 * std::size_t(body_b[lane]) : spare_body;
      lc[j] = c >= 0 ? l + std::size_t(R) * c : spare_rows;
    }
    V va[6], vb[6];
    load_lanes6(wa, va);
    load_lanes6(wb, vb);
    const V ra[3] = {FIBRE_FIELD(9), FIBRE_FIELD(10), FIBRE_FIELD(11)};
    const V rb[3] = {FIBRE_FIELD(12), FIBRE_FIELD(13), FIBRE_FIELD(14)};
    // t = v_a + omega_a x ra - (v_b + omega_b x rb) (contact_velocity)
    V ta[3], tb[3];
    point_velocity(va, ra, ta);
    point_velocity(vb, rb, tb);
    const V t0 = _mm256_sub_pd(ta[0], tb[0]), t1 = _mm256_sub_pd(ta[1], tb[1]),
            t2 = _mm256_sub_pd(ta[2], tb[2]);
    V D[9];
    for (int i = 0; i < 9; ++i) D[i] = FIBRE_FIELD(kFrame + i);
    V u[6];
    frame_rows(D, t0, t1, t2, u);
    if constexpr (R == 6)
      frame_rows(D, _mm256_sub_pd(va[3], vb[3]), _mm256_sub_pd(va[4], vb[4]),
                 _mm256_sub_pd(va[5], vb[5]), u + 3);
    // x = old + (b - u - Sigma old) / scale, then lambda_n >= 0 (NaN and infinity to 0) and
    // each cone (Cones::project_rows)
    V old[R], x[R], delta[R];
    load_rows<R>(lc, old);
    for (int i = 0; i < R; ++i) {
      const V r = _mm256_fnmadd_pd(FIBRE_FIELD(kSigma + i), old[i],
                                   _mm256_sub_pd(FIBRE_FIELD(kRhs + i), u[i]));
      x[i] = _mm256_fmadd_pd(r, FIBRE_FIELD(kScale + i), old[i]);
    }
    project_lanes<R, C>(p, x);
    for (int i = 0; i < R; ++i) {
      delta[i] = _mm256_sub_pd(x[i], old[i]);
      change2 = _mm256_fmadd_pd(delta[i], delta[i], change2);
      size2 = _mm256_fmadd_pd(x[i], x[i], size2);
    }
    store_rows<R>(lc, x);
    add_change<R>(p, D, ra, rb, delta, va, vb);
    store_lanes6(wa, va);
    store_lanes6(wb, vb);
#undef FIBRE_FIELD
  }
  alignas(32) double sums[2][4];
  _mm256_store_pd(sums[0], change2);
  _mm256_store_pd(sums[1], size2);
  for (int j = 0; j < 4; ++j) {
    norms[0] += sums[0][j];
    norms[1] += sums[1][j];
  }
}

} // namespace

void GroupedSweep::sweep(Vector &lambda, Vector &dv, double norms[2])
{
  const int groups = static_cast<int>(contact_.size()) / kGroupLanes;
  const auto run = [&](auto kernel) {
    kernel(pack_.data(), contact_.data(), body_a_.data(), body_b_.data(), groups, lambda.data(),
           dv.data(), norms);
  };
  if (rows_ == 6)
    cohesive_ ? run(sweep_groups<6, true>) : run(sweep_groups<6, false>);
  else
    cohesive_ ? run(sweep_groups<3, true>) : run(sweep_groups<3, false>);
}

#else

bool grouped_sweeps_available()
{
  return false;
}

void GroupedSweep::sweep(Vector &, Vector &, double *)
{
  throw std::logic_error("GroupedSweep::sweep: grouped sweeps need x86-64 with AVX2 and FMA");
}

#endif

} // namespace fibre
