// Contact detection for fix fibre_contact on LAMMPS or LIGGGHTS data: the group's atoms as
// bodies (owned ones sorted by tag, then ghosts), sphere pairs from the granular pair style's
// neighbour list, spheres outside the group as fixed obstacles, plane walls, and the host's
// own walls: LAMMPS regions (fix/region_walls.cpp) or LIGGGHTS meshes
// (liggghts/mesh_walls.cpp). The criteria and geometry are the library's (fibre/detection.hpp,
// fibre/mesh.hpp).
#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "fibre/geometry/detection.hpp"
#include "fibre/model/material.hpp"
#include "pointers.h"

namespace fibre_lmp {

class LammpsExchange;
class LammpsClumps;

class LammpsDetection : protected LAMMPS_NS::Pointers {
 public:
  LammpsDetection(LAMMPS_NS::LAMMPS *lmp, int groupbit, LammpsExchange &exchange);
  ~LammpsDetection() override;

  // Resolves the host's walls (region or mesh IDs); call from init().
  void init_walls(const std::vector<fibre::WallSpec> &walls);
  // Clumps (nullptr: none): no contacts within a clump, and a joint for each member.
  void set_clumps(const LammpsClumps *clumps) { clumps_ = clumps; }
  // The pair style's materials (nullptr: none), for a JKR contact's reach beyond touching.
  void set_materials(const fibre::MaterialTable *materials);
  // At a run's setup: moving regions record their present position, so that the first step's
  // surface velocity is that step's displacement (not the one since the region was defined).
  void start_moving_walls();

  // The step's bodies: velocities and external forces of owned atoms, forwarded to ghosts.
  std::vector<fibre::Body> bodies();

  // The time since the fix was defined, for moving planes (wiggle, shear).
  void set_wall_time(double t) { wall_time_ = t; }

  // Every contact this process keeps, in the library's order (fibre::sort_contacts).
  // impacts: contacts may bounce (restitution), so a body hit within the step may move faster
  // than its own velocity says; the contacts it can then reach are kept too (collective).
  // recovery: how far the split recovery moves a body in a step at most, h_s max_recovery of
  // the contact solve's step h_s (0: none); where the last step opened penetrations
  // (recovering) or a contact overlaps by more than kPenetrationStart times it, every body's
  // reach grows by it.
  fibre::FoundContacts contacts(const std::vector<fibre::Body> &bodies, double h, double damping,
                                bool impacts = false, double recovery = 0.0,
                                bool recovering = false);

 private:
  // pairs of group atoms into `pairs`, a group atom against one outside (an obstacle) into found
  void pair_contacts(const std::vector<fibre::Body> &bodies, double h, double damping,
                     std::vector<fibre::DetectedContact> &found,
                     std::vector<fibre::DetectedPair> &pairs);
  void impact_kicks(const std::vector<fibre::Body> &bodies, double h,
                    const std::vector<fibre::DetectedContact> &found,
                    const std::vector<fibre::DetectedPair> &pairs, fibre::Vector &kick) const;
  void wall_contacts(const std::vector<fibre::Body> &bodies, double h, double damping,
                     std::vector<fibre::DetectedContact> &found) const;
  // A wall contact of body with the wall's surface velocity at the point and angular velocity.
  // wall_radius: the surface's radius of curvature (Contact::wall_radius), 0 for a plane.
  void add_wall_contact(const std::vector<fibre::Body> &bodies, int body, const fibre::Vec3 &n,
                        double distance, int wall, int sub, const fibre::Vec3 &wall_v,
                        const fibre::Vec3 &wall_omega, double wall_radius, double h, double damping,
                        std::vector<fibre::DetectedContact> &found) const;

  double kick(int body) const { return kick_.empty() ? 0.0 : kick_[body]; }
  // fibre::is_contact, and in the impact pass only for the candidates the kicks add; a gap up
  // to `hold` (a JKR pair's reach, hold_reach) is a contact in the first pass
  bool accept(const fibre::Body &a, const fibre::Body *b, const fibre::Vec3 &n, double gap,
              double h, double damping, double kick, double wall_approach = 0.0,
              double hold = 0.0) const;
  // How far apart a contact of types ta, tb (a wall's or obstacle's type for tb) and effective
  // radius r_eff holds once it has touched: its JKR reach, else 0.
  double hold_reach(int ta, int tb, double r_eff) const;

  // The host's walls, one source file per host: regions (LAMMPS) or meshes (LIGGGHTS); the
  // other host's kind is an error at init.
  struct HostWalls;
  void init_host_wall(int wall);
  void host_wall_contacts(int wall, const std::vector<fibre::Body> &bodies, double h,
                          double damping, std::vector<fibre::DetectedContact> &found) const;

  bool same_atoms(int nlocal, int nall);

  int groupbit_;
  LammpsExchange &exchange_;
  std::vector<fibre::WallSpec> walls_;
  const fibre::MaterialTable *materials_ = nullptr; // set when some type pair is JKR
  const LammpsClumps *clumps_ = nullptr;
  double wall_time_ = 0.0;
  std::vector<double> kick_; // per body: the speed an impact may give it this step
  // per listed pair, in the list's order: a contact of the first pass, which the impact pass
  // would only reject again (its accept asks for a contact that the first pass did not take)
  std::vector<unsigned char> taken_;
  std::vector<double> speed_;  // per body: its free speed over this step (fibre::free_speed)
  std::size_t last_found_ = 0; // contacts found in the last step, besides pairs
  std::size_t last_pairs_ = 0; // pairs found in the last step
  std::unique_ptr<HostWalls> host_walls_;
  std::vector<int> atom_body_; // local atom -> body index, -1 if not a body
  // the atoms at the last call of bodies() (same_atoms): the owned count, and per atom its tag
  // and whether it is in the group
  int last_nlocal_ = -1;
  std::vector<std::pair<LAMMPS_NS::tagint, bool>> last_atoms_;
};

} // namespace fibre_lmp
