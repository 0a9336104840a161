// The LAMMPS host's own walls: regions, as fix wall/gran/region sees them. Moving regions
// (move, rotate) give each contact their surface velocity; unions and intersections move with
// their sub-regions.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>

#include "comm.h"
#include "domain.h"
#include "fibre/core/text.hpp"
#include "error.h"
#include "fibre_detect.h"
#include "host.h"
#include "lammps_exchange.h"
#include "neighbor.h"
#include "region.h"

using namespace LAMMPS_NS;

namespace fibre_lmp {

namespace {

bool is_combined(const Region *region)
{
  return std::strcmp(region->style, "union") == 0 || std::strcmp(region->style, "intersect") == 0;
}

// The sub-region that made contact `iwall` of a union or intersect, recursively (the region
// itself when it is not combined). LAMMPS numbers a combined region's contacts by sub-region:
// with `side in` the sub-region's own number plus the cmax of the sub-regions before it, with
// `side out` the sub-region's index in the list.
Region *contact_owner(Domain *domain, Region *region, int iwall)
{
  while (is_combined(region)) {
    Region *owner = nullptr;
    if (!region->interior) {
      if (iwall < 0 || iwall >= region->nregion) return region;
      owner = domain->regions[region->list[iwall]];
      iwall = 0;
    } else {
      for (int i = 0; i < region->nregion && !owner; ++i) {
        Region *sub = domain->regions[region->list[i]];
        if (iwall < sub->cmax)
          owner = sub;
        else
          iwall -= sub->cmax;
      }
      if (!owner) return region;
    }
    region = owner;
  }
  return region;
}

// LAMMPS's Region::set_velocity multiplies the angular speed by the rotation axis as typed
// (omega = dtheta/dt axis), so a region rotating about '1 1 1' would spin its wall sqrt(3) times
// too fast; the fix divides by |axis|. Region::axis is private: an explicit instantiation may
// name it (access checks do not apply to the names in one, C++17 [temp.explicit]/14).
using AxisMember = double (Region::*)[3];
AxisMember region_axis();
template <AxisMember M> struct ExposeAxis {
  friend AxisMember region_axis() { return M; }
};
template struct ExposeAxis<&Region::axis>;

double axis_length(const Region *region)
{
  const double *a = region->*region_axis();
  return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
}

// A rotating (sub-)region's angular velocity about its unit axis.
fibre::Vec3 angular_velocity(const Region *region)
{
  const double len = axis_length(region);
  const fibre::Vec3 w(region->omega[0], region->omega[1], region->omega[2]);
  return len > 0.0 ? fibre::Vec3(w / len) : w;
}

// A moving (sub-)region's surface velocity at point p and its angular velocity, from its
// displacement and rotation over the last step (set_velocity, LAMMPS's differencing).
void surface_velocity(const Region *region, const double *p, fibre::Vec3 &v, fibre::Vec3 &w)
{
  v = region->moveflag ? fibre::Vec3(region->v[0], region->v[1], region->v[2])
                       : fibre::Vec3::Zero();
  w = fibre::Vec3::Zero();
  if (!region->rotateflag) return;
  w = angular_velocity(region);
  const fibre::Vec3 arm(p[0] - region->rpoint[0], p[1] - region->rpoint[1],
                        p[2] - region->rpoint[2]);
  v += w.cross(arm);
}

// A bound of the surface speed of a moving region (and of its moving sub-regions) within the
// sphere's reach: translation plus rotation at the sphere's distance from the axis point.
double speed_bound(Domain *domain, const Region *region, const double *x, double radius)
{
  if (is_combined(region)) {
    double most = 0.0;
    for (int i = 0; i < region->nregion; ++i)
      most = std::max(most, speed_bound(domain, domain->regions[region->list[i]], x, radius));
    return most;
  }
  if (!region->dynamic) return 0.0;
  double speed = region->moveflag
                     ? std::sqrt(region->v[0] * region->v[0] + region->v[1] * region->v[1] +
                                 region->v[2] * region->v[2])
                     : 0.0;
  if (region->rotateflag) {
    const double w = angular_velocity(region).norm();
    const double dx = x[0] - region->rpoint[0], dy = x[1] - region->rpoint[1],
                 dz = x[2] - region->rpoint[2];
    speed += w * (std::sqrt(dx * dx + dy * dy + dz * dz) + radius);
  }
  return speed;
}

// A rotation axis that is not a unit vector: LAMMPS's fix wall/gran/region then moves the wall
// |axis| times too fast; this fix uses the unit axis.
void warn_axis(Domain *domain, Error *error, bool me0, const Region *region)
{
  if (is_combined(region)) {
    for (int i = 0; i < region->nregion; ++i)
      warn_axis(domain, error, me0, domain->regions[region->list[i]]);
    return;
  }
  const double len = region->rotateflag ? axis_length(region) : 1.0;
  if (me0 && std::abs(len - 1.0) > 1e-6)
    warn(error, FLERR,
         "Fix fibre_contact 'wall region': region " + std::string(region->id) +
             " rotates about an axis of length " + fibre::format_g(len) +
             "; LAMMPS's region velocity (and fix wall/gran/region's wall speed) is then that "
             "many times the angular speed, the fix uses the unit axis (type the axis as a "
             "unit vector for a native twin to agree)");
}

} // namespace

// The LAMMPS host's walls are regions (fix wall/gran/region's surfaces); a mesh needs LIGGGHTS.
struct LammpsDetection::HostWalls {
  std::vector<int> regions; // per wall: index in domain->regions, or -1
};

// Constructed and destroyed where HostWalls is complete.
LammpsDetection::LammpsDetection(LAMMPS *lmp, int groupbit, LammpsExchange &exchange)
    : Pointers(lmp), groupbit_(groupbit), exchange_(exchange)
{
}

LammpsDetection::~LammpsDetection() = default;

void LammpsDetection::init_host_wall(int w)
{
  if (!host_walls_) host_walls_ = std::make_unique<HostWalls>();
  std::vector<int> &regions = host_walls_->regions;
  regions.resize(walls_.size(), -1);
  const std::string &id = walls_[w].id;
  if (walls_[w].kind == fibre::WallKind::mesh)
    fail(error, FLERR,
         "Fix fibre_contact 'wall mesh " + id +
             "': mesh walls (fix mesh/surface) need the LIGGGHTS front end, liggghts_fibre; in "
             "LAMMPS use 'wall region <region-ID>'");
  regions[w] = domain->find_region(id);
  if (regions[w] < 0)
    fail(error, FLERR, "Region ID '" + id + "' for fix fibre_contact 'wall region' does not exist");
  Region *region = domain->regions[regions[w]];
  // A union or intersect moves with its sub-regions (contact_owner); with `side out` LAMMPS
  // numbers the contacts of a nested union or intersect by its index only.
  if (is_combined(region) && region->dynamic && !region->interior)
    for (int i = 0; i < region->nregion; ++i) {
      const Region *sub = domain->regions[region->list[i]];
      if (is_combined(sub) && sub->dynamic)
        fail(error, FLERR,
             "Fix fibre_contact 'wall region " + id + "': a moving " + sub->style +
                 " inside a region with 'side out' is not "
                 "supported; list its sub-regions in " +
                 id + " instead");
    }
  warn_axis(domain, error, comm->me == 0, region);
  if (region->varshape)
    fail(error, FLERR,
         "Fix fibre_contact 'wall region " + id +
             "': a region whose shape changes over time (variable radius) is "
             "not supported; 'move' and 'rotate' are");
}

void LammpsDetection::start_moving_walls()
{
  if (!host_walls_) return;
  for (int r : host_walls_->regions) {
    if (r < 0 || !domain->regions[r]->dynamic) continue;
    domain->regions[r]->prematch();
    domain->regions[r]->set_velocity();
  }
}

void LammpsDetection::host_wall_contacts(int w, const std::vector<fibre::Body> &bodies, double h,
                                         double damping,
                                         std::vector<fibre::DetectedContact> &found) const
{
  const int nowned = exchange_.num_owned();
  const double skin = neighbor->skin;
  Region *region = domain->regions[host_walls_->regions[w]];
  region->prematch();
  // the surface velocity of a moving region: its displacement and rotation over the last
  // step (LAMMPS's set_velocity, once per step whoever calls it)
  const bool moving = region->dynamic;
  if (moving) region->set_velocity();
  for (int k = 0; k < nowned; ++k) {
    const fibre::Body &b = bodies[k];
    const double speed = moving ? speed_bound(domain, region, b.x.data(), b.radius) : 0.0;
    const int nc =
        region->surface(b.x[0], b.x[1], b.x[2], fibre::region_cutoff(b, h, damping, skin, speed));
    for (int c = 0; c < nc; ++c) {
      const Region::Contact &rc = region->contact[c];
      if (!(rc.r > 0.0)) continue;
      const fibre::Vec3 n(rc.delx / rc.r, rc.dely / rc.r, rc.delz / rc.r);
      // the surface point's velocity, from the (sub-)region it belongs to
      fibre::Vec3 wall_v = fibre::Vec3::Zero(), wall_omega = fibre::Vec3::Zero();
      if (moving) {
        const double p[3] = {b.x[0] - rc.delx, b.x[1] - rc.dely, b.x[2] - rc.delz};
        surface_velocity(contact_owner(domain, region, rc.iwall), p, wall_v, wall_omega);
      }
      // the region's curvature at the contact, as fix wall/gran/region passes it
      add_wall_contact(bodies, k, n, rc.r, w, std::min(rc.iwall, fibre::kWallKeyStride - 1), wall_v,
                       wall_omega, rc.radius, h, damping, found);
    }
  }
}

} // namespace fibre_lmp
