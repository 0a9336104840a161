#include "fibre_detect.h"

#include <algorithm>
#include <cmath>

#include "atom.h"
#include "error.h"
#include "fibre/model/cohesion.hpp"
#include "fibre/model/contact_model.hpp"
#include "host.h"
#include "force.h"
#include "lammps_clumps.h"
#include "lammps_exchange.h"
#include "neigh_list.h"
#include "neighbor.h"
#include "pair.h"

using namespace LAMMPS_NS;

namespace fibre_lmp {

void LammpsDetection::init_walls(const std::vector<fibre::WallSpec> &walls)
{
  walls_ = walls;
  for (int w = 0; w < static_cast<int>(walls.size()); ++w)
    if (!walls[w].is_primitive()) init_host_wall(w);
}

void LammpsDetection::set_materials(const fibre::MaterialTable *materials)
{
  materials_ = nullptr;
  if (!materials) return;
  for (int i = 1; i <= materials->ntypes(); ++i)
    for (int j = i; j <= materials->ntypes(); ++j)
      if (materials->at(i, j).cohesion == fibre::CohesionLaw::jkr) materials_ = materials;
}

double LammpsDetection::hold_reach(int ta, int tb, double r_eff) const
{
  if (!materials_ || ta < 1 || tb < 1 || ta > materials_->ntypes() || tb > materials_->ntypes())
    return 0.0;
  return fibre::cohesive_reach(materials_->at(ta, tb), r_eff);
}

// Whether the atoms are stored as at the last call: no neighbour build since (LAMMPS exchanges
// and sorts atoms and rebuilds the ghosts only then) and the same tags and group bits, which a
// dynamic group or a command between runs may change. Records them for the next call.
bool LammpsDetection::same_atoms(int nlocal, int nall)
{
  const tagint *tag = atom->tag;
  const int *mask = atom->mask;
  bool same = neighbor->ago > 0 && nlocal == last_nlocal_ &&
              static_cast<std::size_t>(nall) == last_atoms_.size();
  for (int i = 0; same && i < nall; ++i)
    same = last_atoms_[i].first == tag[i] && last_atoms_[i].second == ((mask[i] & groupbit_) != 0);
  if (!same) {
    last_nlocal_ = nlocal;
    last_atoms_.resize(nall);
    for (int i = 0; i < nall; ++i) last_atoms_[i] = {tag[i], (mask[i] & groupbit_) != 0};
  }
  return same;
}

std::vector<fibre::Body> LammpsDetection::bodies()
{
  const int nlocal = atom->nlocal, nall = nlocal + atom->nghost;
  const int *mask = atom->mask;
  const tagint *tag = atom->tag;
  double **x = atom->x;

  // Owned atoms by tag, ghosts by tag and position: the system does not depend on the atoms'
  // storage order. Between neighbour builds the storage order holds, and so does this one.
  if (!same_atoms(nlocal, nall)) {
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
    exchange_.set_bodies(body_atom, nowned);
    atom_body_.assign(nall, -1);
    for (int k = 0; k < static_cast<int>(body_atom.size()); ++k) atom_body_[body_atom[k]] = k;
  }
  const std::vector<int> &body_atom = exchange_.body_atom();
  const int nowned = exchange_.num_owned();
  const int nbody = static_cast<int>(body_atom.size());

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

  // each Body built from its values: default-constructed ones were zeroed first, which took
  // 45% of this function (7% of a step on a stream of free grains)
  std::vector<fibre::Body> out;
  out.reserve(nbody);
  for (int k = 0; k < nbody; ++k) {
    const int i = body_atom[k];
    out.push_back(fibre::Body{atom->rmass[i], atom->radius[i],
                              fibre::Vec3(x[i][0], x[i][1], x[i][2]), vel.segment<3>(6 * k),
                              vel.segment<3>(6 * k + 3), frc.segment<3>(6 * k),
                              frc.segment<3>(6 * k + 3), atom->type[i]});
  }
  return out;
}

fibre::FoundContacts LammpsDetection::contacts(const std::vector<fibre::Body> &bodies, double h,
                                               double damping, bool impacts, double recovery,
                                               bool recovering)
{
  std::vector<fibre::DetectedContact> found;
  std::vector<fibre::DetectedPair> pairs;
  found.reserve(last_found_ + last_found_ / 8 + 16); // about the last step's, without regrowth
  pairs.reserve(last_pairs_ + last_pairs_ / 8 + 16);
  kick_.clear();
  speed_.resize(bodies.size());
  for (std::size_t k = 0; k < bodies.size(); ++k) speed_[k] = fibre::free_speed(bodies[k], h);
  pair_contacts(bodies, h, damping, found, pairs);
  wall_contacts(bodies, h, damping, found);
  // A rigid row's penetration is opened by a displacement of up to `recovery` a step
  // (fibre/step/recovery.hpp), which moves the bodies around it too: every body may move that
  // far, and the contacts it can then reach are kept (the displacement closes none of them).
  // Where the last step recovered, or some overlap is deeper than a penetration's start.
  double deep = recovering ? 1.0 : 0.0;
  if (recovery > 0 && !recovering) {
    for (const fibre::DetectedContact &fc : found)
      if (-fc.contact.gap > fibre::kPenetrationStart * recovery) deep = 1.0;
    for (const fibre::DetectedPair &fp : pairs)
      if (-fp.gap > fibre::kPenetrationStart * recovery) deep = 1.0;
    exchange_.max(&deep, 1);
  }
  if (impacts || deep > 0) {
    const int nbody = static_cast<int>(bodies.size());
    fibre::Vector kick = fibre::Vector::Zero(6 * Eigen::Index(nbody));
    if (impacts) impact_kicks(bodies, h, found, pairs, kick);
    kick_.resize(nbody);
    for (int k = 0; k < nbody; ++k) kick_[k] = kick[6 * k] + (deep > 0 ? recovery / h : 0.0);
    // the second pass adds what the kicks reach; the first pass's contacts stand
    pair_contacts(bodies, h, damping, found, pairs);
    wall_contacts(bodies, h, damping, found);
  }
  if (clumps_) clumps_->joints(bodies, atom_body_, found);
  last_found_ = found.size();
  last_pairs_ = pairs.size();
  return fibre::sort_contacts(std::move(found), std::move(pairs), &bodies);
}

// An impact changes both bodies' velocities within the step by up to twice the approach speed:
// a sphere at rest hit from above would otherwise pass through the floor, whose contact its own
// velocity did not find. Summed over processes (a bound of the maximum); kick: 6 per body,
// the first of each set.
void LammpsDetection::impact_kicks(const std::vector<fibre::Body> &bodies, double h,
                                   const std::vector<fibre::DetectedContact> &found,
                                   const std::vector<fibre::DetectedPair> &pairs,
                                   fibre::Vector &kick) const
{
  const auto add = [&](int a, int b, double approach) {
    if (!(approach > 0.0)) return;
    kick[6 * a] = std::max(kick[6 * a], 2.0 * approach);
    if (b >= 0) kick[6 * b] = std::max(kick[6 * b], 2.0 * approach);
  };
  for (const fibre::DetectedContact &fc : found) {
    const fibre::Contact &c = fc.contact;
    const fibre::Body *b = c.is_wall() ? nullptr : &bodies[c.b];
    add(c.a, c.b, fibre::free_approach(bodies[c.a], b, c.normal, h) + c.normal.dot(c.wall_v));
  }
  for (const fibre::DetectedPair &fp : pairs)
    add(fp.a, fp.b, fibre::free_approach(bodies[fp.a], &bodies[fp.b], fp.normal, h));
  exchange_.reverse_sum(kick);
  exchange_.forward(kick);
}

// In the impact pass (kicks set) a candidate is new only if its kick brings it into reach:
// is_contact grows with the kick, so the first pass took every other contact already.
bool LammpsDetection::accept(const fibre::Body &a, const fibre::Body *b, const fibre::Vec3 &n,
                             double gap, double h, double damping, double kick,
                             double wall_approach, double hold) const
{
  if (kick_.empty())
    return gap <= hold || fibre::is_contact(a, b, n, gap, h, damping, 0.0, wall_approach);
  return !(gap <= hold) && kick > 0.0 &&
         fibre::is_contact(a, b, n, gap, h, damping, kick, wall_approach) &&
         !fibre::is_contact(a, b, n, gap, h, damping, 0.0, wall_approach);
}

// Every contact is kept by exactly one process: a pair of two owned atoms is listed once; with
// newton_pair on a pair with a ghost is listed on one process only; with newton_pair off it is
// listed on both and the process owning the atom with the smaller tag keeps it.
void LammpsDetection::pair_contacts(const std::vector<fibre::Body> &bodies, double h,
                                    double damping, std::vector<fibre::DetectedContact> &found,
                                    std::vector<fibre::DetectedPair> &pairs)
{
  std::string style;
  NeighList *list = fibre_lmp::granular_pair(lmp, style)->list;
  const int nlocal = atom->nlocal;
  const tagint *tag = atom->tag;
  double **x = atom->x, **v = atom->v, **omega = atom->omega;
  const double *radius = atom->radius;
  const bool newton_pair = force->newton_pair != 0;
  const double reach = neighbor->skin; // pairs beyond radsum + skin are not in the list
  const bool impact_pass = !kick_.empty();
  if (!impact_pass) {
    std::size_t listed = 0;
    for (int ii = 0; ii < list->inum; ++ii) listed += list->numneigh[list->ilist[ii]];
    taken_.assign(listed, 0);
  }

  std::size_t pair = 0;
  for (int ii = 0; ii < list->inum; ++ii) {
    const int i = list->ilist[ii];
    const int *jlist = list->firstneigh[i];
    for (int jj = 0; jj < list->numneigh[i]; ++jj, ++pair) {
      const int j = jlist[jj] & NEIGHMASK;
      const int bi = atom_body_[i], bj = atom_body_[j];
      if (bi < 0 && bj < 0) continue;
      if (impact_pass &&
          (taken_[pair] || (!(bi >= 0 && kick_[bi] > 0) && !(bj >= 0 && kick_[bj] > 0))))
        continue;                                   // the impact pass: nothing new within reach
      if (tag[i] == tag[j]) continue;               // a periodic image of itself
      if (clumps_ && clumps_->same(i, j)) continue; // a clump's joint holds them
      if (j >= nlocal && !newton_pair && tag[i] > tag[j]) continue;
      const double dx = x[i][0] - x[j][0], dy = x[i][1] - x[j][1], dz = x[i][2] - x[j][2];
      const double rsq = dx * dx + dy * dy + dz * dz;
      const double radsum = radius[i] + radius[j];
      const double hold =
          materials_ ? hold_reach(atom->type[i], atom->type[j], radius[i] * radius[j] / radsum)
                     : 0.0;
      if (rsq >= (radsum + reach + hold) * (radsum + reach + hold)) continue;
      // the atom with the smaller tag stores the warm start if it is owned here
      const int low = tag[i] < tag[j] ? i : j, high = low == i ? j : i;
      const int store = low < nlocal ? low : high;
      const auto keep = [&](fibre::ContactTag &fc) {
        fc.store = store;
        fc.key = tag[store] == fc.tag_a ? fc.partner : static_cast<double>(fc.tag_a);
      };
      if (bi >= 0 && bj >= 0) {
        const int a = tag[i] < tag[j] ? bi : bj, b = a == bi ? bj : bi;
        // beyond the reach of is_contact (with a margin for round-off): no contact
        const double far =
            (1.0 + 1e-9) * std::max(fibre::pair_reach(radius[i], radius[j], speed_[a], speed_[b], h,
                                                      damping, kick(a) + kick(b)),
                                    radsum + hold);
        if (rsq >= far * far) continue;
        fibre::Vec3 normal;
        double gap = 0.0;
        fibre::sphere_sphere_gap(bodies[a], bodies[b], normal, gap);
        if (!accept(bodies[a], &bodies[b], normal, gap, h, damping, kick(a) + kick(b), 0.0, hold))
          continue;
        fibre::DetectedPair &fp = pairs.emplace_back();
        fp.a = a;
        fp.b = b;
        fp.normal = normal;
        fp.gap = gap;
        fp.tag_a = tag[low];
        fp.partner = static_cast<double>(tag[high]);
        keep(fp);
        taken_[pair] = 1;
      } else {
        // one atom is outside the group: a fixed spherical obstacle
        const int g = bi >= 0 ? i : j, o = g == i ? j : i;
        const double sign = g == i ? 1.0 : -1.0, dist = std::sqrt(rsq);
        fibre::Vec3 n(sign * dx, sign * dy, sign * dz);
        n = dist > 0.0 ? fibre::Vec3(n / dist) : fibre::Vec3::UnitZ();
        fibre::DetectedContact fc;
        fc.contact = fibre::sphere_wall_contact(bodies, atom_body_[g], n, dist - radius[o]);
        fc.contact.wall_type = atom->type[o];
        fc.contact.wall_radius = radius[o];
        // a kinematic obstacle (moved by fix move or another fix): its velocity at the point
        const fibre::Vec3 vo(v[o][0], v[o][1], v[o][2]), wo(omega[o][0], omega[o][1], omega[o][2]);
        const fibre::Vec3 xo(x[o][0], x[o][1], x[o][2]);
        fc.contact.wall_v = vo + wo.cross(fc.contact.point - xo);
        fc.contact.wall_omega = wo;
        if (!accept(bodies[atom_body_[g]], nullptr, n, fc.contact.gap, h, damping,
                    kick(atom_body_[g]), n.dot(fc.contact.wall_v), hold))
          continue;
        fc.tag_a = tag[g];
        fc.partner = static_cast<double>(tag[o]);
        keep(fc);
        found.push_back(std::move(fc));
        taken_[pair] = 1;
      }
    }
  }
}

void LammpsDetection::add_wall_contact(const std::vector<fibre::Body> &bodies, int body,
                                       const fibre::Vec3 &n, double distance, int wall, int sub,
                                       const fibre::Vec3 &wall_v, const fibre::Vec3 &wall_omega,
                                       double wall_radius, double h, double damping,
                                       std::vector<fibre::DetectedContact> &found) const
{
  const int type = bodies[body].type, wall_type = walls_[wall].type;
  const double hold =
      materials_ ? hold_reach(type, wall_type > 0 ? wall_type : type, bodies[body].radius) : 0.0;
  if (!accept(bodies[body], nullptr, n, distance - bodies[body].radius, h, damping, kick(body),
              n.dot(wall_v), hold))
    return;
  fibre::DetectedContact fc;
  fc.contact = fibre::sphere_wall_contact(bodies, body, n, distance);
  fc.contact.wall_v = wall_v;
  fc.contact.wall_omega = wall_omega;
  fc.contact.wall_radius = wall_radius;
  fc.contact.wall_type = walls_[wall].type;
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
    if (walls_[w].is_plane()) {
      for (int k = 0; k < nowned; ++k) {
        fibre::PlaneHit hits[2];
        const int n = fibre::plane_hits(walls_[w], bodies[k], skin, hits, wall_time_);
        for (int s = 0; s < n; ++s) {
          add_wall_contact(bodies, k, hits[s].normal, hits[s].distance, w, hits[s].sub,
                           walls_[w].velocity(wall_time_), fibre::Vec3::Zero(), 0.0, h, damping,
                           found);
        }
      }
      continue;
    }
    if (walls_[w].is_cylinder()) {
      // the curvature fix wall/gran gives a sphere inside a cylinder: -2 R
      for (int k = 0; k < nowned; ++k) {
        fibre::PlaneHit hit;
        if (fibre::cylinder_hit(walls_[w], bodies[k], skin, hit))
          add_wall_contact(bodies, k, hit.normal, hit.distance, w, 0, fibre::Vec3::Zero(),
                           fibre::Vec3::Zero(), -2.0 * walls_[w].radius, h, damping, found);
      }
      continue;
    }
    host_wall_contacts(w, bodies, h, damping, found);
  }
}

} // namespace fibre_lmp
