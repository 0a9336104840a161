#include "fibre_detect.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "atom.h"
#include "domain.h"
#include "error.h"
#include "force.h"
#include "lammps_exchange.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "pair.h"
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

// A moving (sub-)region's surface velocity at point p and its angular velocity, from its
// displacement and rotation over the last step (set_velocity, LAMMPS's differencing).
void surface_velocity(const Region *region, const double *p, fibre::Vec3 &v, fibre::Vec3 &w)
{
  v = region->moveflag ? fibre::Vec3(region->v[0], region->v[1], region->v[2])
                       : fibre::Vec3::Zero();
  w = fibre::Vec3::Zero();
  if (!region->rotateflag) return;
  w = fibre::Vec3(region->omega[0], region->omega[1], region->omega[2]);
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
    const double w =
        std::sqrt(region->omega[0] * region->omega[0] + region->omega[1] * region->omega[1] +
                  region->omega[2] * region->omega[2]);
    const double dx = x[0] - region->rpoint[0], dy = x[1] - region->rpoint[1],
                 dz = x[2] - region->rpoint[2];
    speed += w * (std::sqrt(dx * dx + dy * dy + dz * dz) + radius);
  }
  return speed;
}

} // namespace

LammpsDetection::LammpsDetection(LAMMPS *lmp, int groupbit, LammpsExchange &exchange)
    : Pointers(lmp), groupbit_(groupbit), exchange_(exchange)
{
}

void LammpsDetection::init_walls(const std::vector<fibre::WallSpec> &walls)
{
  walls_ = walls;
  regions_.assign(walls.size(), -1);
  for (std::size_t w = 0; w < walls.size(); ++w) {
    if (walls[w].kind != fibre::WallKind::region) continue;
    const std::string &id = walls[w].region_id;
    regions_[w] = domain->find_region(id);
    if (regions_[w] < 0)
      error->all(FLERR,
                 "Region ID '" + id + "' for fix fibre_contact 'wall region' does not exist");
    Region *region = domain->regions[regions_[w]];
    // A union or intersect moves with its sub-regions (contact_owner); with `side out` LAMMPS
    // numbers the contacts of a nested union or intersect by its index only.
    if (is_combined(region) && region->dynamic && !region->interior)
      for (int i = 0; i < region->nregion; ++i) {
        const Region *sub = domain->regions[region->list[i]];
        if (is_combined(sub) && sub->dynamic)
          error->all(FLERR, "Fix fibre_contact 'wall region " + id + "': a moving " + sub->style +
                                " inside a region with 'side out' is not "
                                "supported; list its sub-regions in " +
                                id + " instead");
      }
    if (region->varshape)
      error->all(FLERR, "Fix fibre_contact 'wall region " + id +
                            "': a region whose shape changes over time (variable radius) is "
                            "not supported; 'move' and 'rotate' are");
  }
}

void LammpsDetection::start_moving_walls()
{
  for (int r : regions_) {
    if (r < 0 || !domain->regions[r]->dynamic) continue;
    domain->regions[r]->prematch();
    domain->regions[r]->set_velocity();
  }
}

std::vector<fibre::Body> LammpsDetection::bodies()
{
  const int nlocal = atom->nlocal, nall = nlocal + atom->nghost;
  const int *mask = atom->mask;
  const tagint *tag = atom->tag;
  double **x = atom->x;

  // Owned atoms by tag, ghosts by tag and position: the system does not depend on the atoms'
  // storage order.
  std::vector<int> body_atom, ghosts;
  for (int i = 0; i < nlocal; ++i)
    if (mask[i] & groupbit_) body_atom.push_back(i);
  for (int i = nlocal; i < nall; ++i)
    if (mask[i] & groupbit_) ghosts.push_back(i);
  std::sort(body_atom.begin(), body_atom.end(), [tag](int a, int b) { return tag[a] < tag[b]; });
  std::sort(ghosts.begin(), ghosts.end(), [tag, x](int a, int b) {
    if (tag[a] != tag[b]) return tag[a] < tag[b];
    for (int d = 0; d < 3; ++d)
      if (x[a][d] != x[b][d]) return x[a][d] < x[b][d];
    return a < b;
  });
  const int nowned = static_cast<int>(body_atom.size());
  body_atom.insert(body_atom.end(), ghosts.begin(), ghosts.end());
  const int nbody = static_cast<int>(body_atom.size());
  exchange_.set_bodies(body_atom, nowned);
  atom_body_.assign(nall, -1);
  for (int k = 0; k < nbody; ++k) atom_body_[body_atom[k]] = k;

  double **v = atom->v, **omega = atom->omega, **f = atom->f, **torque = atom->torque;
  fibre::Vector vel = fibre::Vector::Zero(6 * Eigen::Index(nbody));
  fibre::Vector frc = fibre::Vector::Zero(6 * Eigen::Index(nbody));
  for (int k = 0; k < nowned; ++k) {
    const int i = body_atom[k];
    for (int d = 0; d < 3; ++d) {
      vel[6 * k + d] = v[i][d];
      vel[6 * k + 3 + d] = omega[i][d];
      frc[6 * k + d] = f[i][d];
      frc[6 * k + 3 + d] = torque[i][d];
    }
  }
  exchange_.forward(vel);
  exchange_.forward(frc);

  std::vector<fibre::Body> out(nbody);
  for (int k = 0; k < nbody; ++k) {
    const int i = body_atom[k];
    fibre::Body &b = out[k];
    b.mass = atom->rmass[i];
    b.radius = atom->radius[i];
    b.x = fibre::Vec3(x[i][0], x[i][1], x[i][2]);
    b.v = vel.segment<3>(6 * k);
    b.omega = vel.segment<3>(6 * k + 3);
    b.force = frc.segment<3>(6 * k);
    b.torque = frc.segment<3>(6 * k + 3);
    b.type = atom->type[i];
  }
  return out;
}

std::vector<fibre::DetectedContact>
LammpsDetection::contacts(const std::vector<fibre::Body> &bodies, double h, double damping,
                          bool impacts)
{
  std::vector<fibre::DetectedContact> found;
  kick_.clear();
  pair_contacts(bodies, h, damping, found);
  wall_contacts(bodies, h, damping, found);
  if (impacts) {
    // An impact changes both bodies' velocities within the step by up to twice the approach
    // speed: a sphere at rest hit from above would otherwise pass through the floor, whose
    // contact its own velocity did not find. Summed over processes (a bound of the maximum).
    const int nbody = static_cast<int>(bodies.size());
    fibre::Vector kick = fibre::Vector::Zero(6 * Eigen::Index(nbody));
    for (const fibre::DetectedContact &fc : found) {
      const fibre::Contact &c = fc.contact;
      const fibre::Body *b = c.is_wall() ? nullptr : &bodies[c.b];
      const double approach =
          fibre::free_approach(bodies[c.a], b, c.normal, h) + c.normal.dot(c.wall_v);
      if (!(approach > 0.0)) continue;
      kick[6 * c.a] = std::max(kick[6 * c.a], 2.0 * approach);
      if (!c.is_wall()) kick[6 * c.b] = std::max(kick[6 * c.b], 2.0 * approach);
    }
    exchange_.reverse_sum(kick);
    exchange_.forward(kick);
    kick_.resize(nbody);
    for (int k = 0; k < nbody; ++k) kick_[k] = kick[6 * k];
    found.clear();
    pair_contacts(bodies, h, damping, found);
    wall_contacts(bodies, h, damping, found);
  }
  fibre::sort_contacts(found);
  return found;
}

// Every contact is kept by exactly one process: a pair of two owned atoms is listed once; with
// newton_pair on a pair with a ghost is listed on one process only; with newton_pair off it is
// listed on both and the process owning the atom with the smaller tag keeps it.
void LammpsDetection::pair_contacts(const std::vector<fibre::Body> &bodies, double h,
                                    double damping,
                                    std::vector<fibre::DetectedContact> &found) const
{
  NeighList *list = force->pair->list;
  const int nlocal = atom->nlocal;
  const tagint *tag = atom->tag;
  double **x = atom->x, **v = atom->v, **omega = atom->omega;
  const double *radius = atom->radius;
  const bool newton_pair = force->newton_pair != 0;
  const double reach = neighbor->skin; // pairs beyond radsum + skin are not in the list

  for (int ii = 0; ii < list->inum; ++ii) {
    const int i = list->ilist[ii];
    const int *jlist = list->firstneigh[i];
    for (int jj = 0; jj < list->numneigh[i]; ++jj) {
      const int j = jlist[jj] & NEIGHMASK;
      const int bi = atom_body_[i], bj = atom_body_[j];
      if (bi < 0 && bj < 0) continue;
      if (tag[i] == tag[j]) continue; // a periodic image of itself
      if (j >= nlocal && !newton_pair && tag[i] > tag[j]) continue;
      const double dx = x[i][0] - x[j][0], dy = x[i][1] - x[j][1], dz = x[i][2] - x[j][2];
      const double rsq = dx * dx + dy * dy + dz * dz;
      const double radsum = radius[i] + radius[j];
      if (rsq >= (radsum + reach) * (radsum + reach)) continue;

      // the atom with the smaller tag stores the warm start if it is owned here
      const int low = tag[i] < tag[j] ? i : j, high = low == i ? j : i;
      fibre::DetectedContact fc;
      fc.store = low < nlocal ? low : high;
      if (bi >= 0 && bj >= 0) {
        const int a = tag[i] < tag[j] ? bi : bj, b = a == bi ? bj : bi;
        fc.contact = fibre::sphere_sphere_contact(bodies, a, b);
        if (!fibre::is_contact(bodies[a], &bodies[b], fc.contact.normal, fc.contact.gap, h, damping,
                               kick(a) + kick(b)))
          continue;
        fc.tag_a = tag[low];
        fc.partner = static_cast<double>(tag[high]);
      } else {
        // one atom is outside the group: a fixed spherical obstacle
        const int g = bi >= 0 ? i : j, o = g == i ? j : i;
        const double sign = g == i ? 1.0 : -1.0, dist = std::sqrt(rsq);
        fibre::Vec3 n(sign * dx, sign * dy, sign * dz);
        n = dist > 0.0 ? fibre::Vec3(n / dist) : fibre::Vec3::UnitZ();
        fc.contact = fibre::sphere_wall_contact(bodies, atom_body_[g], n, dist - radius[o]);
        fc.contact.wall_type = atom->type[o];
        // a kinematic obstacle (moved by fix move or another fix): its velocity at the point
        const fibre::Vec3 vo(v[o][0], v[o][1], v[o][2]), wo(omega[o][0], omega[o][1], omega[o][2]);
        const fibre::Vec3 xo(x[o][0], x[o][1], x[o][2]);
        fc.contact.wall_v = vo + wo.cross(fc.contact.point - xo);
        fc.contact.wall_omega = wo;
        if (!fibre::is_contact(bodies[atom_body_[g]], nullptr, n, fc.contact.gap, h, damping,
                               kick(atom_body_[g]), n.dot(fc.contact.wall_v)))
          continue;
        fc.tag_a = tag[g];
        fc.partner = static_cast<double>(tag[o]);
      }
      fc.key = tag[fc.store] == fc.tag_a ? fc.partner : static_cast<double>(fc.tag_a);
      found.push_back(fc);
    }
  }
}

void LammpsDetection::add_wall_contact(const std::vector<fibre::Body> &bodies, int body,
                                       const fibre::Vec3 &n, double distance, int wall, int sub,
                                       const fibre::Vec3 &wall_v, const fibre::Vec3 &wall_omega,
                                       double h, double damping,
                                       std::vector<fibre::DetectedContact> &found) const
{
  if (!fibre::is_contact(bodies[body], nullptr, n, distance - bodies[body].radius, h, damping,
                         kick(body), n.dot(wall_v)))
    return;
  fibre::DetectedContact fc;
  fc.contact = fibre::sphere_wall_contact(bodies, body, n, distance);
  fc.contact.wall_v = wall_v;
  fc.contact.wall_omega = wall_omega;
  fc.store = exchange_.body_atom()[body];
  fc.tag_a = atom->tag[fc.store];
  fc.partner = fibre::wall_key(wall, sub);
  fc.key = fc.partner;
  fc.wall = wall;
  found.push_back(fc);
}

void LammpsDetection::wall_contacts(const std::vector<fibre::Body> &bodies, double h,
                                    double damping,
                                    std::vector<fibre::DetectedContact> &found) const
{
  const int nowned = exchange_.num_owned();
  const double skin = neighbor->skin;
  for (int w = 0; w < static_cast<int>(walls_.size()); ++w) {
    if (walls_[w].kind != fibre::WallKind::region) {
      for (int k = 0; k < nowned; ++k) {
        fibre::PlaneHit hits[2];
        const int n = fibre::plane_hits(walls_[w], bodies[k], skin, hits, wall_time_);
        for (int s = 0; s < n; ++s) {
          add_wall_contact(bodies, k, hits[s].normal, hits[s].distance, w, hits[s].sub,
                           walls_[w].velocity(wall_time_), fibre::Vec3::Zero(), h, damping, found);
        }
      }
      continue;
    }
    Region *region = domain->regions[regions_[w]];
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
        add_wall_contact(bodies, k, n, rc.r, w, std::min(rc.iwall, fibre::kWallKeyStride - 1),
                         wall_v, wall_omega, h, damping, found);
      }
    }
  }
}

} // namespace fibre_lmp
