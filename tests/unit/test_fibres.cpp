// Fibres (thesis Algorithm 4), the relabelling and the spanning forest, checked against
// properties computed here from the contact list alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <set>

#include "fibre/algebra/kernels.hpp"
#include "fibre/algebra/operators.hpp"
#include "fibre/precond/fibres.hpp"
#include "fibre/scenes.hpp"

using namespace fibre;

namespace {

const EdgeWeight kWeights[] = {EdgeWeight::z, EdgeWeight::straight, EdgeWeight::impulse};

// The same bodies and contacts with the last `ghosts` bodies marked as halo copies.
ContactSystem with_ghosts(const ContactSystem &sys, int ghosts)
{
  ContactSystem out(sys.bodies(), sys.contacts(), sys.rows(), sys.params(),
                    sys.num_bodies() - ghosts);
  out.set_rhs(sys.rhs());
  return out;
}

Vector some_impulses(const ContactSystem &sys, unsigned seed)
{
  std::srand(seed);
  return Vector::Random(sys.num_contacts()).cwiseAbs();
}

bool is_edge(const ContactSystem &sys, const Contact &k, bool ghosts)
{
  const int limit = ghosts ? sys.num_bodies() : sys.num_owned_bodies();
  return !k.is_wall() && k.a < limit && k.b < limit;
}

// Every property of doc/design.md section 3 and fibres.hpp, from the contact list.
void expect_valid_fibres(const ContactSystem &sys, const Fibres &f, bool ghosts)
{
  const std::vector<Contact> &cs = sys.contacts();
  ASSERT_EQ(f.body_start.size(), f.contact_start.size());
  std::vector<int> fibre_of(sys.num_bodies(), -1);
  std::set<int> used_contacts;
  for (int k = 0; k < f.num_fibres(); ++k) {
    const int nb = f.body_start[k + 1] - f.body_start[k];
    ASSERT_GE(nb, 2) << "fibre " << k;
    ASSERT_EQ(f.length(k), nb - 1);
    for (int p = f.body_start[k]; p < f.body_start[k + 1]; ++p) {
      const int i = f.bodies[p];
      EXPECT_EQ(fibre_of[i], -1) << "body " << i << " is in two fibres";
      fibre_of[i] = k;
      if (!ghosts) {
        EXPECT_LT(i, sys.num_owned_bodies());
      }
    }
    for (int q = 0; q < f.length(k); ++q) {
      const int c = f.contacts[f.contact_start[k] + q];
      EXPECT_TRUE(used_contacts.insert(c).second);
      ASSERT_TRUE(is_edge(sys, cs[c], ghosts));
      const int u = f.bodies[f.body_start[k] + q], v = f.bodies[f.body_start[k] + q + 1];
      EXPECT_TRUE((cs[c].a == u && cs[c].b == v) || (cs[c].a == v && cs[c].b == u))
          << "contact " << c << " does not join fibre bodies " << u << ", " << v;
      if (q > 0) {
        const Contact &prev = cs[f.contacts[f.contact_start[k] + q - 1]];
        const int shared =
            (prev.a == cs[c].a) + (prev.a == cs[c].b) + (prev.b == cs[c].a) + (prev.b == cs[c].b);
        EXPECT_EQ(shared, 1);
      }
    }
  }
  // Maximality: (i) no fibre end touches an uncovered body, (ii) no two uncovered bodies
  // touch.
  std::vector<char> is_end(sys.num_bodies(), 0);
  for (int k = 0; k < f.num_fibres(); ++k) {
    is_end[f.bodies[f.body_start[k]]] = 1;
    is_end[f.bodies[f.body_start[k + 1] - 1]] = 1;
  }
  for (const Contact &k : cs) {
    if (!is_edge(sys, k, ghosts)) continue;
    const bool a_free = fibre_of[k.a] < 0, b_free = fibre_of[k.b] < 0;
    EXPECT_FALSE(a_free && b_free) << "uncovered bodies " << k.a << " and " << k.b << " touch";
    EXPECT_FALSE(is_end[k.a] && b_free) << "fibre end " << k.a << " extendable by " << k.b;
    EXPECT_FALSE(is_end[k.b] && a_free) << "fibre end " << k.b << " extendable by " << k.a;
  }
  // Statistics.
  int edges = 0;
  for (const Contact &k : cs) edges += is_edge(sys, k, ghosts);
  EXPECT_EQ(f.stats.num_contacts, edges);
  EXPECT_EQ(f.stats.num_fibres, f.num_fibres());
  EXPECT_EQ(f.stats.contacts_in_fibres, static_cast<int>(f.contacts.size()));
  int count = 0, total = 0;
  for (std::size_t len = 0; len < f.stats.length_histogram.size(); ++len) {
    count += f.stats.length_histogram[len];
    total += static_cast<int>(len) * f.stats.length_histogram[len];
  }
  EXPECT_EQ(count, f.num_fibres());
  EXPECT_EQ(total, static_cast<int>(f.contacts.size()));
  std::map<int, int> lengths;
  for (int k = 0; k < f.num_fibres(); ++k) ++lengths[f.length(k)];
  for (const auto &[len, n] : lengths) EXPECT_EQ(f.stats.length_histogram.at(len), n);
  if (edges > 0) {
    EXPECT_DOUBLE_EQ(f.stats.covered_fraction(), double(f.contacts.size()) / edges);
  }
}

std::vector<int> fibre_bodies(const Fibres &f, int k)
{
  return std::vector<int>(f.bodies.begin() + f.body_start[k],
                          f.bodies.begin() + f.body_start[k + 1]);
}

} // namespace

TEST(Fibres, WeightNames)
{
  for (EdgeWeight w : kWeights) {
    EdgeWeight back = EdgeWeight::z;
    ASSERT_TRUE(parse(to_string(w), back));
    EXPECT_EQ(back, w);
  }
  EdgeWeight w;
  EXPECT_FALSE(parse("diagonal", w));
}

// Grid bodies 3 i + k sit at x = 2 i, z = 2 k. The walks below were traced by hand.
TEST(Fibres, GridZWeightSweepsRows)
{
  const ContactSystem sys = grid_scene(SceneParams{});
  const Fibres f = build_fibres(sys, EdgeWeight::z, nullptr, true);
  ASSERT_EQ(f.num_fibres(), 1);
  EXPECT_EQ(fibre_bodies(f, 0), (std::vector<int>{0, 3, 6, 7, 4, 1, 2, 5, 8}));
  expect_valid_fibres(sys, f, true);
}

TEST(Fibres, GridStraightWeightSpirals)
{
  const ContactSystem sys = grid_scene(SceneParams{});
  const Fibres f = build_fibres(sys, EdgeWeight::straight, nullptr, true);
  ASSERT_EQ(f.num_fibres(), 1);
  EXPECT_EQ(fibre_bodies(f, 0), (std::vector<int>{0, 3, 6, 7, 8, 5, 2, 1, 4}));
  expect_valid_fibres(sys, f, true);
}

TEST(Fibres, GridImpulseWeightFollowsLoadedColumns)
{
  const ContactSystem sys = grid_scene(SceneParams{});
  Vector impulses(sys.num_contacts());
  for (int c = 0; c < sys.num_contacts(); ++c) {
    const Contact &k = sys.contacts()[c];
    const bool vertical = std::abs(sys.bodies()[k.a].x.z() - sys.bodies()[k.b].x.z()) > 1.0;
    impulses[c] = vertical ? 1.0 : 0.0;
  }
  const Fibres f = build_fibres(sys, EdgeWeight::impulse, &impulses, true);
  ASSERT_EQ(f.num_fibres(), 1);
  EXPECT_EQ(fibre_bodies(f, 0), (std::vector<int>{0, 1, 2, 5, 4, 3, 6, 7, 8}));
  // No impulses yet: the weight falls back to z.
  EXPECT_EQ(build_fibres(sys, EdgeWeight::impulse, nullptr, true).bodies,
            build_fibres(sys, EdgeWeight::z, nullptr, true).bodies);
  const Vector wrong(3);
  EXPECT_THROW(build_fibres(sys, EdgeWeight::impulse, &wrong, true), std::invalid_argument);
}

// Bodies 1 - 0 - 2 in a row: the z walk from 0 goes to the level body 1 and is stuck. The walk
// must go on backwards from 0 to 2; Algorithm 4 as printed would stop there, and 2 (whose only
// neighbour is taken) would stay uncovered next to the fibre end 0.
TEST(Fibres, FibreGrowsBothWaysFromItsStart)
{
  std::vector<Body> bodies(3);
  for (Body &b : bodies) b.radius = 0.5;
  bodies[1].x = Vec3(1, 0, 0); // level with 0
  bodies[2].x = Vec3(0, 0, 1); // above 0
  std::vector<Contact> cs{sphere_sphere_contact(bodies, 2, 0), sphere_sphere_contact(bodies, 1, 0)};
  for (Contact &k : cs) k.compliance.fill(1e-8);
  const ContactSystem sys(bodies, cs, 6, SpookParams{});
  const Fibres f = build_fibres(sys, EdgeWeight::z, nullptr, true);
  ASSERT_EQ(f.num_fibres(), 1);
  EXPECT_EQ(fibre_bodies(f, 0), (std::vector<int>{2, 0, 1}));
  EXPECT_EQ(f.contacts, (std::vector<int>{0, 1}));
  expect_valid_fibres(sys, f, true);
}

TEST(Fibres, PilesAllWeightsWithAndWithoutGhosts)
{
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    SceneParams p;
    p.seed = seed;
    const ContactSystem full = pile_scene(300, p);
    const ContactSystem ghosted = with_ghosts(full, 60);
    const Vector impulses = some_impulses(full, unsigned(seed));
    for (EdgeWeight w : kWeights)
      for (const ContactSystem *sys : {&full, &ghosted})
        for (bool ghosts : {true, false}) {
          SCOPED_TRACE(std::string(to_string(w)) + (ghosts ? " ghosts" : " owned"));
          const Fibres f = build_fibres(*sys, w, &impulses, ghosts);
          expect_valid_fibres(*sys, f, ghosts);
          EXPECT_GT(f.stats.covered_fraction(), 0.2);
        }
  }
}

// Each weight wins on its own criterion: z gives the flattest fibres, straight the least bent,
// impulse the most loaded (the pile's network is sparse, so the margins are modest).
TEST(Fibres, EachWeightOptimisesItsCriterion)
{
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    SceneParams p;
    p.seed = seed;
    const ContactSystem sys = pile_scene(300, p);
    const Vector impulses = some_impulses(sys, unsigned(seed));
    double dz[3], bend[3], load[3];
    std::vector<int> contacts[3];
    for (int m = 0; m < 3; ++m) {
      const Fibres f = build_fibres(sys, kWeights[m], &impulses, true);
      contacts[m] = f.contacts;
      dz[m] = bend[m] = load[m] = 0;
      for (int c : f.contacts) {
        const Contact &k = sys.contacts()[c];
        dz[m] += std::abs(sys.bodies()[k.a].x.z() - sys.bodies()[k.b].x.z()) / f.contacts.size();
        load[m] += impulses[c] / f.contacts.size();
      }
      int joints = 0;
      for (int k = 0; k < f.num_fibres(); ++k)
        for (int q = f.body_start[k] + 1; q + 1 < f.body_start[k + 1]; ++q) {
          const Vec3 e1 = sys.bodies()[f.bodies[q]].x - sys.bodies()[f.bodies[q - 1]].x;
          const Vec3 e2 = sys.bodies()[f.bodies[q + 1]].x - sys.bodies()[f.bodies[q]].x;
          bend[m] += 1.0 - std::abs(e1.dot(e2)) / (e1.norm() * e2.norm());
          ++joints;
        }
      bend[m] /= joints;
    }
    EXPECT_NE(contacts[0], contacts[1]);
    EXPECT_NE(contacts[0], contacts[2]);
    EXPECT_NE(contacts[1], contacts[2]);
    EXPECT_LT(dz[0], std::min(dz[1], dz[2]));
    EXPECT_LT(bend[1], std::min(bend[0], bend[2]));
    EXPECT_GT(load[2], std::max(load[0], load[1]));
  }
}

TEST(Fibres, EdgeWeights)
{
  const ContactSystem sys = grid_scene(SceneParams{});
  // Contact 0 joins bodies 3 (x = 2, z = 0) and 0 (origin); contact 1 joins 1 (z = 2) and 0.
  EXPECT_DOUBLE_EQ(edge_weight(sys, EdgeWeight::z, nullptr, 0, 0, Vec3::Zero()), 0.0);
  EXPECT_DOUBLE_EQ(edge_weight(sys, EdgeWeight::z, nullptr, 1, 0, Vec3::Zero()), 2.0);
  EXPECT_NEAR(edge_weight(sys, EdgeWeight::straight, nullptr, 0, 0, Vec3(1, 0, 1)),
              1.0 - std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(edge_weight(sys, EdgeWeight::straight, nullptr, 1, 0, Vec3(0, 0, -3)), 0.0, 1e-15);
  Vector imp = Vector::Zero(sys.num_contacts());
  imp[1] = 2.5;
  EXPECT_DOUBLE_EQ(edge_weight(sys, EdgeWeight::impulse, &imp, 1, 0, Vec3::Zero()), -2.5);
}

TEST(Forest, SpanningForestProperties)
{
  for (EdgeWeight w : kWeights)
    for (int ghosts : {0, 50})
      for (bool include : {true, false}) {
        SCOPED_TRACE(std::string(to_string(w)) + " ghosts " + std::to_string(ghosts) +
                     (include ? " included" : " excluded"));
        const ContactSystem sys = with_ghosts(pile_scene(250, SceneParams{}), ghosts);
        const Vector impulses = some_impulses(sys, 3);
        const Forest t = build_forest(sys, w, &impulses, include);
        const Fibres fib = build_fibres(sys, w, &impulses, include);
        const int limit = include ? sys.num_bodies() : sys.num_owned_bodies();
        ASSERT_EQ(static_cast<int>(t.order.size()), limit);
        std::vector<int> pos(sys.num_bodies(), -1);
        for (int n = 0; n < limit; ++n) pos[t.order[n]] = n;
        for (int i = 0; i < limit; ++i) ASSERT_GE(pos[i], 0);
        // Components of the body graph, by a flood fill of our own.
        std::vector<std::vector<int>> adj(sys.num_bodies());
        for (const Contact &k : sys.contacts())
          if (is_edge(sys, k, include)) {
            adj[k.a].push_back(k.b);
            adj[k.b].push_back(k.a);
          }
        std::vector<int> comp(sys.num_bodies(), -1);
        int ncomp = 0;
        for (int s = 0; s < limit; ++s) {
          if (comp[s] >= 0) continue;
          std::vector<int> todo{s};
          comp[s] = ncomp;
          while (!todo.empty()) {
            const int i = todo.back();
            todo.pop_back();
            for (int j : adj[i])
              if (comp[j] < 0) {
                comp[j] = ncomp;
                todo.push_back(j);
              }
          }
          ++ncomp;
        }
        int edges = 0;
        std::set<int> tree_contacts;
        for (int i = 0; i < limit; ++i) {
          const int p = t.parent[i];
          if (p < 0) {
            EXPECT_EQ(t.parent_contact[i], -1);
            continue;
          }
          ++edges;
          EXPECT_GT(pos[p], pos[i]) << "parent listed before child";
          const Contact &k = sys.contacts()[t.parent_contact[i]];
          EXPECT_TRUE((k.a == i && k.b == p) || (k.a == p && k.b == i));
          EXPECT_TRUE(is_edge(sys, k, include));
          tree_contacts.insert(t.parent_contact[i]);
        }
        for (int i = limit; i < sys.num_bodies(); ++i) EXPECT_EQ(t.parent[i], -1);
        // A spanning forest: one root per component and n - components edges.
        EXPECT_EQ(edges, limit - ncomp);
        EXPECT_EQ(t.num_edges, edges);
        EXPECT_EQ(static_cast<int>(tree_contacts.size()), edges);
        for (int c : fib.contacts) EXPECT_TRUE(tree_contacts.count(c)) << "fibre contact left out";
        int trees = 0, hist_edges = 0;
        for (std::size_t len = 0; len < t.stats.length_histogram.size(); ++len) {
          trees += t.stats.length_histogram[len];
          hist_edges += static_cast<int>(len) * t.stats.length_histogram[len];
        }
        EXPECT_EQ(trees, t.stats.num_fibres);
        EXPECT_EQ(hist_edges, edges);
        EXPECT_EQ(t.stats.contacts_in_fibres, edges);
        // Kruskal's cycle property over the non-fibre edges: every non-tree edge is no lighter
        // (weight, then index) than each non-fibre edge on the tree path it closes.
        std::set<int> fibre_set(fib.contacts.begin(), fib.contacts.end());
        auto key = [&](int c) {
          const Contact &k = sys.contacts()[c];
          const double wt = w == EdgeWeight::impulse
                                ? -impulses[c]
                                : std::abs(sys.bodies()[k.a].x.z() - sys.bodies()[k.b].x.z());
          return std::make_pair(wt, c);
        };
        std::vector<int> depth(sys.num_bodies(), 0);
        for (auto it = t.order.rbegin(); it != t.order.rend(); ++it)
          if (t.parent[*it] >= 0) depth[*it] = depth[t.parent[*it]] + 1;
        for (int c = 0; c < sys.num_contacts(); ++c) {
          const Contact &k = sys.contacts()[c];
          if (!is_edge(sys, k, include) || tree_contacts.count(c)) continue;
          int u = k.a, v = k.b;
          while (u != v) {
            if (depth[u] < depth[v]) std::swap(u, v);
            const int e = t.parent_contact[u];
            ASSERT_GE(e, 0) << "non-tree edge joins two trees";
            if (!fibre_set.count(e)) {
              EXPECT_LT(key(e), key(c));
            }
            u = t.parent[u];
          }
        }
      }
}

TEST(Fibres, EmptyAndWallOnlySystems)
{
  std::vector<Body> bodies(3);
  for (int i = 0; i < 3; ++i) bodies[i].x = Vec3(3.0 * i, 0, 0.99);
  std::vector<Contact> cs;
  for (int i = 0; i < 3; ++i) {
    cs.push_back(sphere_wall_contact(bodies, i, Vec3::UnitZ(), 0.99));
    cs.back().compliance.fill(1e-8);
  }
  const ContactSystem sys(bodies, cs, 6, SpookParams{});
  const Fibres f = build_fibres(sys, EdgeWeight::z, nullptr, true);
  EXPECT_EQ(f.num_fibres(), 0);
  EXPECT_EQ(f.stats.num_contacts, 0);
  EXPECT_EQ(f.stats.covered_fraction(), 0.0);
  const Forest t = build_forest(sys, EdgeWeight::z, nullptr, true);
  EXPECT_EQ(t.num_edges, 0);
  EXPECT_EQ(t.order.size(), 3u);
  const ContactSystem empty({}, {}, 6, SpookParams{});
  EXPECT_EQ(build_fibres(empty, EdgeWeight::straight, nullptr, false).num_fibres(), 0);
  EXPECT_TRUE(build_forest(empty, EdgeWeight::z, nullptr, false).order.empty());
}
