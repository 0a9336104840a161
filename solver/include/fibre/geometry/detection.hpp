// Contact detection without a front end: which sphere pairs and sphere-wall pairs enter the
// step's contact system, the plane walls' geometry, and the one order of the contacts. The
// front ends supply candidates (neighbour lists, regions, meshes) and atom tags.
#pragma once

#include <string>
#include <vector>

#include "fibre/core/names.hpp"
#include "fibre/core/system.hpp"

namespace fibre {

// Pairs closer than this fraction of the smaller radius are always contacts (resting
// neighbours, no flicker).
inline constexpr double kContactMargin = 0.01;
// Wall contacts are keyed by wall and sub-wall (plane lo/hi, a region's sub-surface).
inline constexpr int kWallKeyStride = 1024;
inline double wall_key(int wall, int sub)
{
  return -static_cast<double>(wall * kWallKeyStride + sub + 1);
}
// Mesh contacts are keyed by wall and triangle ID, below every wall_key (exact in a double up to
// 2^53: 2^40 triangle IDs over 1024 walls).
inline constexpr double kMeshKeyBase = 1099511627776.0; // 2^40
inline double mesh_key(int wall, long triangle)
{
  return -(kMeshKeyBase + static_cast<double>(triangle) * kWallKeyStride + wall + 1);
}

// A wall: one or two planes normal to an axis (lo below, hi above the grains), a region of the
// front end (LAMMPS), or a triangle mesh of the front end (LIGGGHTS fix mesh/surface), named by
// its ID.
// A cylinder (x/y/zcylinder: fix wall/gran's and LIGGGHTS's primitive) holds the grains inside
// it: radius, and the axis's position in the other two coordinates (y z, z x or x y).
enum class WallKind { xplane, yplane, zplane, region, mesh, xcylinder, ycylinder, zcylinder };
template <> struct EnumNames<WallKind> {
  static constexpr EnumName<WallKind> table[] = {
      {WallKind::xplane, "xplane"},       {WallKind::yplane, "yplane"},
      {WallKind::zplane, "zplane"},       {WallKind::region, "region"},
      {WallKind::mesh, "mesh"},           {WallKind::xcylinder, "xcylinder"},
      {WallKind::ycylinder, "ycylinder"}, {WallKind::zcylinder, "zcylinder"}};
};

// How a plane wall moves (fix wall/gran's keywords): wiggle = oscillation along motion_axis,
// amplitude * sin(2 pi t / period) (the planes move when that is their own axis, else they
// slide in their plane); shear = sliding in the plane at shear_speed along motion_axis.
enum class WallMotion { none, wiggle, shear };

struct WallSpec {
  WallKind kind = WallKind::zplane;
  bool has_lo = false, has_hi = false;
  double lo = 0.0, hi = 0.0;
  std::string id; // region or mesh: the front end's region ID or mesh fix ID
  WallMotion motion = WallMotion::none;
  int motion_axis = 0;
  double amplitude = 0.0, period = 1.0, shear_speed = 0.0;
  // The wall's material (per-type coefficients): its contacts take the pair (sphere type,
  // type); 0: the sphere's type with itself. `model` holds the interaction words of the fix
  // wall/gran that the wall replaces ("granular hertz/material 1e5 0.3 0.3 ...", "hooke/history
  // kn kt ..."), which the front end reads into a type of its own.
  int type = 0;
  std::vector<std::string> model;
  double radius = 0.0, centre[2] = {0.0, 0.0}; // cylinders
  // planes and cylinders: 0 x, 1 y, 2 z
  int axis() const
  {
    return is_cylinder() ? static_cast<int>(kind) - static_cast<int>(WallKind::xcylinder)
                         : static_cast<int>(kind);
  }
  bool is_plane() const { return kind <= WallKind::zplane; }
  bool is_cylinder() const { return kind >= WallKind::xcylinder; }
  // walls whose geometry is the library's own (planes, cylinders), not the front end's
  bool is_primitive() const { return is_plane() || is_cylinder(); }
  // The planes' displacement along their own axis and their velocity at time t since the
  // wall was defined.
  double offset(double t) const;
  Vec3 velocity(double t) const;
};

// A pair is a contact when its gap is below kContactMargin of the smaller radius, or when it
// could close within about (damping + 1) steps at its free-flight approach speed over this
// step: SPOOK then brakes the approach before the spheres overlap. b == nullptr: a wall or a
// fixed obstacle. n points from b (the wall) to a. A contact with a positive gap never pulls:
// its impulse would be negative and the solve releases it.
// How fast a approaches b (or a wall at rest, b == nullptr) along n after a step of free flight
// under their external forces; negative when they separate. n points from b to a.
double free_approach(const Body &a, const Body *b, const Vec3 &n, double h);
// kick: a speed the bodies may gain within the step from impacts (any direction).
// wall_approach: a moving wall's or obstacle's speed towards a along n (n . its velocity).
bool is_contact(const Body &a, const Body *b, const Vec3 &n, double gap, double h, double damping,
                double kick = 0.0, double wall_approach = 0.0);
// A body's speed after a step of free flight, |v + h f / m|.
double free_speed(const Body &b, double h);
// The centre distance beyond which is_contact rejects a pair of spheres of radii ra, rb whose
// free speeds (free_speed) are sa, sb, with the kick of is_contact: a cheap test before the
// pair's normal and gap (many listed neighbours are further apart).
inline double pair_reach(double ra, double rb, double sa, double sb, double h, double damping,
                         double kick = 0.0)
{
  return ra + rb + kContactMargin * (ra < rb ? ra : rb) + (damping + 1.0) * h * (kick + sa + sb);
}

// How far from a sphere a region wall is looked for: its radius, the margin, and its
// free-flight reach over (damping + 1) steps, capped at the neighbour skin; wall_speed bounds
// the speed of a moving wall's surface near the sphere.
double region_cutoff(const Body &b, double h, double damping, double skin, double wall_speed = 0.0);

// The planes of a plane wall within `reach` of the sphere's surface: normal (into the grains),
// centre distance and sub-wall (0 lo, 1 hi). Returns how many (0, 1 or 2) were written.
struct PlaneHit {
  Vec3 normal;
  double distance;
  int sub;
};
// t: time since the wall was defined (moving planes).
int plane_hits(const WallSpec &wall, const Body &b, double reach, PlaneHit hits[2], double t = 0.0);
// A cylinder wall within `reach` of the sphere's surface (the sphere inside it): the normal
// towards the axis and the centre's distance from the surface. Returns 0 or 1.
int cylinder_hit(const WallSpec &wall, const Body &b, double reach, PlaneHit &hit);

// What a step keeps of a found contact besides its Contact: the tags that order it, its wall,
// the atom that stores its history and the key it is stored under, and its gap as found (the
// system's advances over substeps).
struct ContactTag {
  long long tag_a = 0; // the tag of body a (the smaller tag of a pair)
  double partner = 0;  // tag of body b or of an obstacle atom (> 0), or wall_key() (< 0)
  int wall = -1;       // index of the wall, else -1
  int store = -1;      // local atom that keeps the contact's warm start
  double key = 0;      // the key under which `store` keeps it: the other side's tag or key
  double gap = 0;
};

// One contact found by a front end, before the system is built.
struct DetectedContact : ContactTag {
  Contact contact;
};

// A pair of spheres found by a front end: its Contact (sphere_sphere_contact of a, b, normal
// and ContactTag::gap) is built once the step's contacts are sorted, so the search and the sort
// move a few dozen bytes a pair, not a Contact's hundreds.
struct DetectedPair : ContactTag {
  int a = -1, b = -1;
  Vec3 normal = Vec3::UnitZ();
};

// A step's contacts: tags[c] is contacts[c]'s. The contacts go into the system; the tags stay
// for the history and the outputs.
struct FoundContacts {
  std::vector<Contact> contacts;
  std::vector<ContactTag> tags;
};

// The one order of a step's contacts, independent of storage order and process count:
// by tag_a, then partner, then gap; each contact moved once, each pair's built in its place.
FoundContacts sort_contacts(std::vector<DetectedContact> &&found,
                            std::vector<DetectedPair> &&pairs = {},
                            const std::vector<Body> *bodies = nullptr);

} // namespace fibre
