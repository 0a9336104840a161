// Cohesive normal laws (doc/design.md section 2, "Cohesion"), each on the pair's Hertz law
// F_H(d) = k_n sqrt(r_eff d) d, k_n = 4/3 E_eff (positive F pushes the bodies apart):
//   jkr   LAMMPS granular's JKR: contact radius a from d = a^2 / r - 2 sqrt(pi gamma a / E),
//         F = 4 E a^3 / (3 r) - 4 sqrt(pi gamma E a^3), E = E_eff; a contact that has touched
//         holds until d = -reach (LAMMPS's delta_pulloff), where F = -3 pi gamma r;
//   dmt   LAMMPS granular's DMT: F = F_H(d) - 4 pi gamma r while the bodies overlap;
//   sjkr  LIGGGHTS's simplified JKR: F = F_H(d) - k_c A, A = 2 pi r d the contact area,
//         while they overlap.
// In the step a cohesive contact's normal row carries a tension down to the law's pull-off
// force (the cone shifted by h times it) and relaxes to the law's force at its overlap.
#pragma once

#include "fibre/model/material.hpp"

namespace fibre {

// The largest tension (> 0) the law carries: 3 pi gamma r_eff (jkr), 4 pi gamma r_eff (dmt),
// 4 c^3 / (27 K^2) with c = 2 pi r_eff k_c, K = k_n sqrt(r_eff) (sjkr, at d = (2c / 3K)^2);
// 0 without cohesion.
double pull_off_force(const PairCoefficients &p, double r_eff);

// How far apart (a positive gap) a contact that has touched holds: JKR's |delta_pulloff|, 0
// for the other laws.
double cohesive_reach(const PairCoefficients &p, double r_eff);

// The law's normal force at overlap d (negative: tension), down to JKR's d = -reach; at
// smaller d the pull-off force's tension (jkr), -4 pi gamma r (dmt) or 0 (sjkr).
double cohesive_force(const PairCoefficients &p, double r_eff, double overlap);

// The overlap at which the law carries force f on its stable branch (where the force grows
// with the overlap); f at or below the pull-off tension gives the branch's smallest overlap.
double cohesive_overlap(const PairCoefficients &p, double r_eff, double f);

// The coefficient of restitution of a head-on impact at approach speed v under the cohesive
// law and the pair's normal damper (reduced mass m_eff): the law integrated from the first
// touch until the bodies part (at JKR's reach, or where the overlap ends), or 0 where the
// adhesion holds them (they close again, or stay 20 collision times). -1 without cohesion. The
// law is not scale free, so each impact is integrated (200 steps per Hertz collision time).
double cohesive_restitution(const PairCoefficients &p, double m_eff, double r_eff, double v);

} // namespace fibre
