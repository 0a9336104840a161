// One contact's rows of G without forming them: the per-contact arithmetic that the products
// (kernels.cpp) and the projected Gauss-Seidel sweeps (pgs.cpp) share. D is the contact frame
// (column-major 3x3, rows n, t1, t2), ra and rb the levers, as ContactKinematics stores them.
#pragma once

namespace fibre {

// u (R rows) = G_c w for contact c with frame D (column-major 3x3), levers ra, rb.
#if defined(__GNUC__)
#define FIBRE_INLINE inline __attribute__((always_inline))
#else
#define FIBRE_INLINE inline
#endif

template <int R>
FIBRE_INLINE void contact_velocity(const double *D, const double *ra, const double *rb,
                                   const double *wa, const double *wb, double *u)
{
  // t = v_a + omega_a x ra (- v_b - omega_b x rb), o = omega_a (- omega_b)
  double t0 = wa[0] + wa[4] * ra[2] - wa[5] * ra[1];
  double t1 = wa[1] + wa[5] * ra[0] - wa[3] * ra[2];
  double t2 = wa[2] + wa[3] * ra[1] - wa[4] * ra[0];
  double o0 = wa[3], o1 = wa[4], o2 = wa[5];
  if (wb) {
    t0 -= wb[0] + wb[4] * rb[2] - wb[5] * rb[1];
    t1 -= wb[1] + wb[5] * rb[0] - wb[3] * rb[2];
    t2 -= wb[2] + wb[3] * rb[1] - wb[4] * rb[0];
    o0 -= wb[3];
    o1 -= wb[4];
    o2 -= wb[5];
  }
  for (int i = 0; i < 3; ++i) u[i] = D[i] * t0 + D[i + 3] * t1 + D[i + 6] * t2;
  if (R == 6)
    for (int i = 0; i < 3; ++i) u[3 + i] = D[i] * o0 + D[i + 3] * o1 + D[i + 6] * o2;
}

// Adds G_c^T l into the body vectors ya and (if not a wall) yb.
template <int R>
FIBRE_INLINE void contact_impulse(const double *D, const double *ra, const double *rb,
                                  const double *l, double *ya, double *yb)
{
  double f[3], m[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) f[k] = D[3 * k] * l[0] + D[3 * k + 1] * l[1] + D[3 * k + 2] * l[2];
  if (R == 6)
    for (int k = 0; k < 3; ++k) m[k] = D[3 * k] * l[3] + D[3 * k + 1] * l[4] + D[3 * k + 2] * l[5];
  ya[0] += f[0];
  ya[1] += f[1];
  ya[2] += f[2];
  ya[3] += ra[1] * f[2] - ra[2] * f[1] + m[0];
  ya[4] += ra[2] * f[0] - ra[0] * f[2] + m[1];
  ya[5] += ra[0] * f[1] - ra[1] * f[0] + m[2];
  if (!yb) return;
  yb[0] -= f[0];
  yb[1] -= f[1];
  yb[2] -= f[2];
  yb[3] -= rb[1] * f[2] - rb[2] * f[1] + m[0];
  yb[4] -= rb[2] * f[0] - rb[0] * f[2] + m[1];
  yb[5] -= rb[0] * f[1] - rb[1] * f[0] + m[2];
}

} // namespace fibre
