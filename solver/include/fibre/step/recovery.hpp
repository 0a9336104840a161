// Split recovery of penetrations (design notes, "Penetrations"). A rigid normal row whose
// overlap is more than a step's recovery and closing explain, or an elastic row whose overlap
// is that much more than its load explains (Contact::penetration, set by the contact model),
// asks the velocity solve for no separation (SpookParams::split_penetration), and the
// penetration is removed by a displacement of the bodies of at most max_recovery * h a step,
// which adds no velocity.
// A sphere caged in others (created inside a bed) has no rigid solution that separates it:
// asked to separate at max_recovery, the velocity solve threw it out at up to 93 m/s; the
// displacement only moves it as far as its cage lets it. Bullet's and PhysX's split impulse
// keep penetration recovery out of the velocity solve for the same reason.
#pragma once

#include "fibre/core/exchange.hpp"
#include "fibre/core/system.hpp"

namespace fibre {

// How many contacts of all processes have a penetration that the split recovery opens
// (SpookParams::split_penetration; collective).
long split_penetrations(const ContactSystem &sys, const Exchange &ex);

// What recovery_displacement did, alike on every process.
struct Recovery {
  enum class Outcome {
    none,    // no process has a split penetration: dx untouched
    opened,  // dx opens them
    refused, // no room (a jammed pack): dx is zero
  };
  Outcome outcome = Outcome::none;
  long split = 0; // split_penetrations
};

// The displacement of every body (6 per body, owned and ghosts; the rotations zero) that opens
// the split penetrations left after the step (the gaps advanced by h G v_plus, h the system's)
// by at most span max_recovery, without closing any other contact by more than its gap: the
// frictionless impulse problem G M^-1 G^T mu + Sigma mu = b, mu >= 0, in at most max_sweeps
// sweeps, and each body's displacement at most span max_recovery (a cage with no room ends the
// sweeps unconverged, with impulses that grow). A displacement that closes other contacts by
// most of what it opens (a jammed pack, more spheres than its box holds) is not taken: dx is
// zero, and the penetrations stay until there is room. span is the step the displacement is
// taken over: the system's h, or the whole step where the system is its last substep's.
// sys's elastic normal rows are rigid during the solve and restored on return. Collective.
Recovery recovery_displacement(ContactSystem &sys, const Exchange &ex, const Vector &v_plus,
                               double span, Vector &dx, int max_sweeps = 100);

// An elastic row's penetration left after the displacement dx: springs[c][0] (the penetration
// left after the step, Substeps::springs) less the opening G_n dx of a split one, so that the
// history's penetration shrinks by what the displacement removed, not only with the overlap
// (its load's overlap is then the spring's).
void take_opening(const ContactSystem &sys, const Vector &dx,
                  std::vector<std::array<double, kMaxRows>> &springs);

} // namespace fibre
