#include "fibre/scenes.hpp"

#include "fibre/algebra/spook.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

namespace fibre {

namespace {

void set_compliance(std::vector<Contact> &contacts, double eps)
{
  for (Contact &c : contacts) c.compliance.fill(eps);
}

void randomize_motion(std::vector<Body> &bodies, std::mt19937_64 &rng)
{
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Body &b : bodies) {
    b.v = Vec3(u(rng), u(rng), u(rng));
    b.omega = Vec3(u(rng), u(rng), u(rng));
    b.force = Vec3(0, 0, -9.81 * b.mass);
  }
}

ContactSystem finish(std::vector<Body> bodies, std::vector<Contact> contacts, const SceneParams &p)
{
  set_compliance(contacts, p.compliance);
  ContactSystem sys(std::move(bodies), std::move(contacts), p.rows, p.spook);
  sys.set_rhs(spook_rhs(sys));
  return sys;
}

} // namespace

ContactSystem grid_scene(const SceneParams &p)
{
  std::mt19937_64 rng(p.seed);
  std::vector<Body> bodies;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      Body b;
      b.radius = 1.0;
      b.mass = 1.0;
      b.x = Vec3(2.0 * i, 0.0, 2.0 * k);
      bodies.push_back(b);
    }
  randomize_motion(bodies, rng);
  std::vector<Contact> contacts;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      const int id = 3 * i + k;
      if (i + 1 < 3) contacts.push_back(sphere_sphere_contact(bodies, id + 3, id));
      if (k + 1 < 3) contacts.push_back(sphere_sphere_contact(bodies, id + 1, id));
    }
  return finish(std::move(bodies), std::move(contacts), p);
}

ContactSystem pile_scene(int n, const SceneParams &p)
{
  std::mt19937_64 rng(p.seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double rmin = 0.5, rmax = 1.0, rmean = 0.75;
  // Box side for a pile about 8 layers high.
  const double side = std::max(4.0 * rmean, 2.2 * rmean * std::sqrt(n / 8.0));
  std::vector<Body> bodies;
  bodies.reserve(n);
  for (int i = 0; i < n; ++i) {
    Body b;
    b.radius = rmin + (rmax - rmin) * uni(rng);
    b.mass = b.radius * b.radius * b.radius; // unit density up to 4 pi / 3
    const double x = b.radius + (side - 2 * b.radius) * uni(rng);
    const double y = b.radius + (side - 2 * b.radius) * uni(rng);
    double z = b.radius; // resting on the floor
    for (const Body &o : bodies) {
      const double dx = x - o.x.x(), dy = y - o.x.y(), reach = b.radius + o.radius;
      const double d2 = dx * dx + dy * dy;
      if (d2 < reach * reach) z = std::max(z, o.x.z() + std::sqrt(reach * reach - d2));
    }
    b.x = Vec3(x, y, z);
    bodies.push_back(b);
  }
  randomize_motion(bodies, rng);
  // Contacts: every pair within tolerance (a cell list keeps this O(n)), plus the floor.
  const double tol = p.contact_tolerance * rmean, reach = 2 * rmax + tol;
  const int ncell = std::max(1, static_cast<int>(side / reach));
  const double cell = side / ncell;
  double zmax = 0;
  for (const Body &b : bodies) zmax = std::max(zmax, b.x.z());
  const int nz = static_cast<int>(zmax / cell) + 1;
  auto cell_of = [&](const Vec3 &x, int &cx, int &cy, int &cz) {
    cx = std::min(ncell - 1, std::max(0, static_cast<int>(x.x() / cell)));
    cy = std::min(ncell - 1, std::max(0, static_cast<int>(x.y() / cell)));
    cz = std::min(nz - 1, std::max(0, static_cast<int>(x.z() / cell)));
  };
  std::vector<std::vector<int>> cells(std::size_t(ncell) * ncell * nz);
  for (int i = 0; i < n; ++i) {
    int cx, cy, cz;
    cell_of(bodies[i].x, cx, cy, cz);
    cells[(std::size_t(cz) * ncell + cy) * ncell + cx].push_back(i);
  }
  std::uniform_real_distribution<double> overlap(0.0, p.max_overlap * rmean);
  std::vector<Contact> contacts;
  for (int i = 0; i < n; ++i) {
    int cx, cy, cz;
    cell_of(bodies[i].x, cx, cy, cz);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = cx + dx, y = cy + dy, z = cz + dz;
          if (x < 0 || y < 0 || z < 0 || x >= ncell || y >= ncell || z >= nz) continue;
          for (int j : cells[(std::size_t(z) * ncell + y) * ncell + x]) {
            if (j <= i) continue;
            const double dist = (bodies[i].x - bodies[j].x).norm();
            if (dist - bodies[i].radius - bodies[j].radius < tol) {
              // Upper body first, so that the normal points up the pile.
              const bool i_up = bodies[i].x.z() >= bodies[j].x.z();
              Contact c = sphere_sphere_contact(bodies, i_up ? i : j, i_up ? j : i);
              c.gap = std::min(c.gap, 0.0) - overlap(rng);
              contacts.push_back(c);
            }
          }
        }
    if (bodies[i].x.z() - bodies[i].radius < tol) {
      Contact c = sphere_wall_contact(bodies, i, Vec3::UnitZ(), bodies[i].x.z());
      c.gap = std::min(c.gap, 0.0) - overlap(rng);
      contacts.push_back(c);
    }
  }
  return finish(std::move(bodies), std::move(contacts), p);
}

ContactSystem pair_scene(const SceneParams &p)
{
  std::mt19937_64 rng(p.seed);
  std::vector<Body> bodies(2);
  bodies[0].radius = 1.0;
  bodies[0].mass = 2.0;
  bodies[0].x = Vec3(0.1, 0.2, 1.95);
  bodies[1].radius = 0.8;
  bodies[1].mass = 1.0;
  bodies[1].x = Vec3(0.0, 0.0, 0.2);
  randomize_motion(bodies, rng);
  std::vector<Contact> contacts{sphere_sphere_contact(bodies, 0, 1)};
  return finish(std::move(bodies), std::move(contacts), p);
}

ContactSystem packing_scene(std::vector<Body> bodies, const std::vector<Plane> &walls,
                            const SceneParams &p)
{
  const int n = static_cast<int>(bodies.size());
  double rmean = 0, rmax = 0;
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const Body &b : bodies) {
    rmean += b.radius / std::max(n, 1);
    rmax = std::max(rmax, b.radius);
    lo = lo.cwiseMin(b.x);
    hi = hi.cwiseMax(b.x);
  }
  const double tol = p.contact_tolerance * rmean;
  // Cell list with cells no smaller than the largest interaction distance.
  const double cell = 2 * rmax + tol;
  Eigen::Vector3i dims;
  for (int k = 0; k < 3; ++k) dims[k] = std::max(1, static_cast<int>((hi[k] - lo[k]) / cell) + 1);
  auto cell_index = [&](const Vec3 &x, int k) {
    return std::min(dims[k] - 1, std::max(0, static_cast<int>((x[k] - lo[k]) / cell)));
  };
  std::vector<std::vector<int>> cells(std::size_t(dims[0]) * dims[1] * dims[2]);
  auto flat = [&](int x, int y, int z) { return (std::size_t(z) * dims[1] + y) * dims[0] + x; };
  for (int i = 0; i < n; ++i)
    cells[flat(cell_index(bodies[i].x, 0), cell_index(bodies[i].x, 1), cell_index(bodies[i].x, 2))]
        .push_back(i);
  std::vector<Contact> contacts;
  for (int i = 0; i < n; ++i) {
    const int cx = cell_index(bodies[i].x, 0), cy = cell_index(bodies[i].x, 1),
              cz = cell_index(bodies[i].x, 2);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = cx + dx, y = cy + dy, z = cz + dz;
          if (x < 0 || y < 0 || z < 0 || x >= dims[0] || y >= dims[1] || z >= dims[2]) continue;
          for (int j : cells[flat(x, y, z)]) {
            if (j <= i) continue;
            const double gap =
                (bodies[i].x - bodies[j].x).norm() - bodies[i].radius - bodies[j].radius;
            if (gap >= tol) continue;
            const bool i_up = bodies[i].x.z() >= bodies[j].x.z();
            contacts.push_back(sphere_sphere_contact(bodies, i_up ? i : j, i_up ? j : i));
          }
        }
    for (const Plane &w : walls) {
      const double distance = w.normal.dot(bodies[i].x) - w.offset;
      if (distance - bodies[i].radius < tol)
        contacts.push_back(sphere_wall_contact(bodies, i, w.normal, distance));
    }
  }
  set_compliance(contacts, p.compliance);
  ContactSystem sys(std::move(bodies), std::move(contacts), p.rows, p.spook);
  sys.set_rhs(spook_rhs(sys));
  return sys;
}

std::vector<Body> read_sphere_dump(const std::string &path, double gravity)
{
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open sphere dump '" + path + "'");
  std::string line;
  std::vector<std::string> columns;
  while (std::getline(in, line))
    if (line.rfind("ITEM: ATOMS", 0) == 0) {
      std::istringstream head(line.substr(11));
      for (std::string c; head >> c;) columns.push_back(c);
      break;
    }
  const std::vector<std::string> need = {"id", "radius", "mass", "x", "y", "z", "vx", "vy", "vz"};
  if (columns.size() < need.size() || !std::equal(need.begin(), need.end(), columns.begin()))
    throw std::runtime_error("sphere dump '" + path +
                             "' needs columns: id radius mass x y z vx vy vz");
  const bool has_omega = columns.size() >= 12 && columns[9] == "omegax";
  std::vector<Body> bodies;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    std::vector<double> v;
    for (double x; row >> x;) v.push_back(x);
    if (v.empty()) continue;
    if (v.size() != columns.size())
      throw std::runtime_error("sphere dump '" + path + "': row with " + std::to_string(v.size()) +
                               " values, expected " + std::to_string(columns.size()));
    Body b;
    b.radius = v[1];
    b.mass = v[2];
    b.x = Vec3(v[3], v[4], v[5]);
    b.v = Vec3(v[6], v[7], v[8]);
    if (has_omega) b.omega = Vec3(v[9], v[10], v[11]);
    b.force = Vec3(0, 0, -gravity * b.mass);
    bodies.push_back(b);
  }
  if (bodies.empty()) throw std::runtime_error("sphere dump '" + path + "' has no atoms");
  return bodies;
}

ContactSystem lammps_pile_scene(const std::string &dump_path, const SceneParams &p)
{
  const std::vector<Plane> walls = {{Vec3::UnitZ(), 0.0},
                                    {Vec3::UnitX(), 0.0},
                                    {-Vec3::UnitX(), -8.0},
                                    {Vec3::UnitY(), 0.0},
                                    {-Vec3::UnitY(), -8.0}};
  SceneParams q = p;
  q.contact_tolerance = 0.0; // the Hertz overlaps themselves
  return packing_scene(read_sphere_dump(dump_path), walls, q);
}

} // namespace fibre
