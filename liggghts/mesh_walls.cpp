// The LIGGGHTS host's own walls: triangle meshes of fix mesh/surface (static, or moved by fix
// move/mesh, or with a conveyor's surface velocity). Each step the process's local and ghost
// triangles are read with their node velocities, and go into a grid of the library's
// (fibre/mesh.hpp) when a node has moved; each owned sphere keeps one contact per face, edge or
// vertex it touches, keyed by the triangle's global ID (warm starts follow the triangle). A
// LAMMPS region needs the LAMMPS front end.
#include <mpi.h>

#include <algorithm>
#include <memory>
#include <string>

#include "error.h"
#include "fibre/geometry/mesh.hpp"
#include "fibre_detect.h"
#include "fix_mesh_surface.h"
#include "host.h"
#include "lammps_exchange.h"
#include "modify.h"
#include "neighbor.h"
#include "tri_mesh.h"

using namespace LAMMPS_NS;

namespace fibre_lmp {

// A mesh's triangles of the last search and their grid, rebuilt only when a node has moved
// (a static mesh's grid was rebuilt every step, 4% of the hopper's run, and twice with impacts).
struct MeshCache {
  std::vector<fibre::Triangle> triangles;
  fibre::TriangleGrid grid;
  bool built = false;
};

struct LammpsDetection::HostWalls {
  std::vector<FixMeshSurface *> meshes; // per wall, or nullptr
  std::vector<bool> described;          // per wall: its triangles and open edges logged
  std::vector<MeshCache> cache;         // per wall
  std::vector<fibre::Triangle> fresh;   // the triangles as read this time
  std::vector<fibre::TriangleHit> hits;
  fibre::MeshScratch scratch;
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
  host_walls_->meshes.resize(walls_.size(), nullptr);
  host_walls_->described.assign(walls_.size(), false);
  host_walls_->cache.assign(walls_.size(), MeshCache());
  const std::string &id = walls_[w].id;
  if (walls_[w].kind == fibre::WallKind::region)
    fail(error, FLERR,
         "Fix fibre_contact 'wall region " + id +
             "': LIGGGHTS regions are not walls for this fix; give the wall as a mesh ('fix ID "
             "all mesh/surface file F.stl type T' and 'wall mesh ID') or a plane ('wall zplane "
             "lo hi')");
  Fix *fix = modify->find_fix_id(id.c_str());
  if (!fix)
    fail(error, FLERR,
         "Fix fibre_contact 'wall mesh " + id + "': no fix with ID " + id + " (expected 'fix " +
             id + " all mesh/surface file F.stl type T')");
  if (!starts_with(fix->style, "mesh/surface"))
    fail(error, FLERR,
         "Fix fibre_contact 'wall mesh " + id + "': fix " + id + " is a " + fix->style +
             ", expected a fix mesh/surface");
  host_walls_->meshes[w] = static_cast<FixMeshSurface *>(fix);
}

// fix move/mesh moves the nodes itself and sets their velocities; each run logs its meshes.
void LammpsDetection::start_moving_walls()
{
  if (host_walls_) host_walls_->described.assign(walls_.size(), false);
}

namespace {

// The local and ghost triangles of a mesh, with node velocities where the mesh moves.
void read_triangles(TriMesh *mesh, std::vector<fibre::Triangle> &out)
{
  const int n = mesh->sizeLocal() + mesh->sizeGhost();
  auto *velocity = mesh->prop().getElementProperty<MultiVectorContainer<double, 3, 3>>("v");
  out.resize(n);
  for (int t = 0; t < n; ++t) {
    fibre::Triangle &tri = out[t];
    tri.id = mesh->id(t);
    for (int j = 0; j < 3; ++j) {
      double p[3];
      mesh->node(t, j, p);
      tri.p[j] = fibre::Vec3(p[0], p[1], p[2]);
      tri.v[j] = velocity
                     ? fibre::Vec3((*velocity)(t)[j][0], (*velocity)(t)[j][1], (*velocity)(t)[j][2])
                     : fibre::Vec3::Zero();
    }
  }
}

// The same triangles at the same places (their velocities may differ).
bool same_places(const std::vector<fibre::Triangle> &a, const std::vector<fibre::Triangle> &b)
{
  if (a.size() != b.size()) return false;
  for (std::size_t t = 0; t < a.size(); ++t)
    if (a[t].id != b[t].id || a[t].p[0] != b[t].p[0] || a[t].p[1] != b[t].p[1] ||
        a[t].p[2] != b[t].p[2])
      return false;
  return true;
}

// The whole mesh on process 0 (every process's local triangles): its size and open edges for
// the log, once per run. Collective.
void describe_mesh(LAMMPS *lmp, TriMesh *mesh, const std::string &id)
{
  const int nlocal = mesh->sizeLocal();
  std::vector<double> mine(9 * std::size_t(nlocal));
  for (int t = 0; t < nlocal; ++t)
    for (int j = 0; j < 3; ++j) mesh->node(t, j, &mine[9 * std::size_t(t) + 3 * j]);
  int nprocs = 1, me = 0;
  MPI_Comm_size(lmp->world, &nprocs);
  MPI_Comm_rank(lmp->world, &me);
  const int count = 9 * nlocal;
  std::vector<int> counts(nprocs), offsets(nprocs, 0);
  MPI_Gather(&count, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, lmp->world);
  for (int p = 1; p < nprocs; ++p) offsets[p] = offsets[p - 1] + counts[p - 1];
  std::vector<double> all(me == 0 ? std::size_t(offsets.back() + counts.back()) : 0);
  MPI_Gatherv(mine.data(), count, MPI_DOUBLE, all.data(), counts.data(), offsets.data(), MPI_DOUBLE,
              0, lmp->world);
  if (me != 0) return;
  std::vector<fibre::Triangle> tris(all.size() / 9);
  double edges = 0.0;
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int j = 0; j < 3; ++j) {
      const double *p = &all[9 * t + 3 * j];
      tris[t].p[j] = fibre::Vec3(p[0], p[1], p[2]);
    }
  for (const fibre::Triangle &tri : tris) edges += (tri.p[1] - tri.p[0]).norm();
  const double tol = tris.empty() ? 1.0 : 1e-6 * edges / double(tris.size());
  const int open = fibre::open_edges(tris, tol);
  logmesg(lmp, "fix fibre_contact: wall mesh " + id + ": " + std::to_string(tris.size()) +
                   " triangles, " + std::to_string(open) +
                   (open ? " open edges (rims or holes: grains can leave there)\n"
                         : " open edges (a closed surface)\n"));
}

} // namespace

void LammpsDetection::host_wall_contacts(int w, const std::vector<fibre::Body> &bodies, double h,
                                         double damping,
                                         std::vector<fibre::DetectedContact> &found) const
{
  HostWalls &host = *host_walls_;
  FixMeshSurface *fix = host.meshes[w];
  if (!host.described[w]) {
    describe_mesh(lmp, fix->triMesh(), walls_[w].id);
    host.described[w] = true;
  }
  MeshCache &mesh = host.cache[w];
  read_triangles(fix->triMesh(), host.fresh);
  const bool moved = !mesh.built || !same_places(host.fresh, mesh.triangles);
  mesh.triangles.swap(host.fresh);
  if (mesh.triangles.empty()) return;
  if (moved) {
    mesh.grid.build(mesh.triangles, 0.0);
    mesh.built = true;
  }
  double speed = 0.0; // the fastest node bounds the surface speed near any sphere
  for (const fibre::Triangle &tri : mesh.triangles)
    for (const fibre::Vec3 &v : tri.v) speed = std::max(speed, v.norm());
  const int mesh_type = fix->min_type();
  const int nowned = exchange_.num_owned();
  for (int k = 0; k < nowned; ++k) {
    const fibre::Body &b = bodies[k];
    const double reach = fibre::region_cutoff(b, h, damping, neighbor->skin, speed);
    host.hits.clear();
    fibre::mesh_hits(mesh.triangles, mesh.grid, b.x, reach, host.hits, host.scratch);
    for (const fibre::TriangleHit &hit : host.hits) {
      const std::size_t before = found.size();
      add_wall_contact(bodies, k, hit.normal, hit.distance, w, 0, hit.velocity, fibre::Vec3::Zero(),
                       0.0, h, damping, found);
      if (found.size() == before) continue;
      fibre::DetectedContact &fc = found.back();
      fc.partner = fc.key = fibre::mesh_key(w, mesh.triangles[hit.triangle].id);
      fc.contact.wall_type = mesh_type;
    }
  }
}

} // namespace fibre_lmp
