#include "fibre/model/stress.hpp"

namespace fibre {

void contact_virial(const ContactSystem &sys, const Vector &lambda, Virial &global,
                    Vector *per_body)
{
  global.fill(0.0);
  if (per_body) per_body->setZero(6 * Eigen::Index(sys.num_bodies()));
  const double inv_h = 1.0 / sys.params().h;
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    const double *l = lambda.data() + Eigen::Index(sys.rows()) * c;
    const Vec3 f = inv_h * (l[0] * k.normal + l[1] * k.t1 + l[2] * k.t2); // on body a
    const Body &a = sys.bodies()[k.a];
    const Vec3 r =
        k.is_wall() ? Vec3((a.radius + k.gap) * k.normal) : Vec3(a.x - sys.bodies()[k.b].x);
    const Virial v = {r.x() * f.x(), r.y() * f.y(), r.z() * f.z(),
                      r.x() * f.y(), r.x() * f.z(), r.y() * f.z()};
    for (int i = 0; i < 6; ++i) global[i] += v[i];
    if (!per_body) continue;
    const double share = k.is_wall() ? 1.0 : 0.5;
    for (int i = 0; i < 6; ++i) {
      (*per_body)[6 * k.a + i] += share * v[i];
      if (!k.is_wall()) (*per_body)[6 * k.b + i] += share * v[i];
    }
  }
}

void wall_loads(const ContactSystem &sys, const Vector &lambda, const std::vector<int> &wall_of,
                int num_walls, std::vector<WallLoad> &loads)
{
  loads.assign(num_walls, WallLoad{});
  if (lambda.size() == 0) return;
  const double inv_h = 1.0 / sys.params().h;
  const int rows = sys.rows();
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const int w = wall_of[c];
    if (w < 0 || w >= num_walls) continue;
    const Contact &k = sys.contacts()[c];
    const double *l = lambda.data() + Eigen::Index(rows) * c;
    const Vec3 f = -inv_h * (l[0] * k.normal + l[1] * k.t1 + l[2] * k.t2); // on the wall
    const Body &a = sys.bodies()[k.a];
    const Vec3 q = a.x - (a.radius + k.gap) * k.normal;
    Vec3 torque = q.cross(f);
    if (rows == 6) torque -= inv_h * (l[3] * k.normal + l[4] * k.t1 + l[5] * k.t2);
    for (int i = 0; i < 3; ++i) {
      loads[w][i] += f[i];
      loads[w][3 + i] += torque[i];
    }
  }
}

} // namespace fibre
