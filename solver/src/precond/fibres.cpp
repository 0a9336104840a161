#include "fibre/precond/fibres.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace fibre {

ContactGraph contact_graph(const ContactSystem &sys, bool include_ghosts)
{
  const int nb = sys.num_bodies(), nc = sys.num_contacts();
  const int limit = include_ghosts ? nb : sys.num_owned_bodies();
  // The flat body pairs (8 bytes a contact) instead of the Contact records (160 bytes).
  const int *pairs = sys.body_pairs();
  auto is_edge = [&](int a, int b) { return b >= 0 && a < limit && b < limit; };
  ContactGraph g;
  g.start.assign(std::size_t(nb) + 1, 0);
  for (int c = 0; c < nc; ++c) {
    const int a = pairs[2 * std::size_t(c)], b = pairs[2 * std::size_t(c) + 1];
    if (is_edge(a, b)) {
      ++g.start[a + 1];
      ++g.start[b + 1];
      ++g.num_edges;
    }
  }
  for (int i = 0; i < nb; ++i) g.start[i + 1] += g.start[i];
  g.neighbour.resize(std::size_t(2) * g.num_edges);
  g.contact.resize(std::size_t(2) * g.num_edges);
  std::vector<int> fill(g.start.begin(), g.start.end() - 1);
  for (int c = 0; c < nc; ++c) {
    const int a = pairs[2 * std::size_t(c)], b = pairs[2 * std::size_t(c) + 1];
    if (!is_edge(a, b)) continue;
    g.neighbour[fill[a]] = b;
    g.contact[fill[a]++] = c;
    g.neighbour[fill[b]] = a;
    g.contact[fill[b]++] = c;
  }
  return g;
}

namespace {

void check_impulses(const ContactSystem &sys, EdgeWeight weight, const Vector *impulses)
{
  if (weight == EdgeWeight::impulse && impulses && impulses->size() != sys.num_contacts())
    throw std::invalid_argument("impulse weight needs one normal impulse per contact");
}

// Edge weights for the walk, on flat copies of the positions (the walk's inner loop).
class WalkWeight {
 public:
  WalkWeight(const ContactSystem &sys, EdgeWeight weight, const Vector *impulses)
      : weight_(impulses || weight != EdgeWeight::impulse ? weight : EdgeWeight::z),
        impulses_(impulses ? impulses->data() : nullptr), pos_(3 * std::size_t(sys.num_bodies()))
  {
    for (int i = 0; i < sys.num_bodies(); ++i)
      for (int d = 0; d < 3; ++d) pos_[3 * std::size_t(i) + d] = sys.bodies()[i].x[d];
  }
  // Contact c from body `from` to `to`; prev: the previous edge of the fibre, or zero.
  double operator()(int c, int from, int to, const Vec3 &prev) const
  {
    const double *x = &pos_[3 * std::size_t(from)], *y = &pos_[3 * std::size_t(to)];
    switch (weight_) {
    case EdgeWeight::z:
      return std::abs(y[2] - x[2]);
    case EdgeWeight::impulse:
      return -impulses_[c];
    case EdgeWeight::straight:
      break;
    }
    const double pn = prev.squaredNorm();
    if (pn == 0) return 0.0; // first edge of a fibre: no preference
    const Vec3 e(y[0] - x[0], y[1] - x[1], y[2] - x[2]);
    const double norms = std::sqrt(e.squaredNorm() * pn);
    return norms > 0 ? 1.0 - std::abs(e.dot(prev)) / norms : 1.0;
  }
  // The weight without the walk's history, for the Kruskal completion of the forest.
  double fixed(int c, int from, int to) const
  {
    if (weight_ == EdgeWeight::impulse) return -impulses_[c];
    return std::abs(pos_[3 * std::size_t(to) + 2] - pos_[3 * std::size_t(from) + 2]);
  }
  Vec3 direction(int from, int to) const
  {
    const double *x = &pos_[3 * std::size_t(from)], *y = &pos_[3 * std::size_t(to)];
    return Vec3(y[0] - x[0], y[1] - x[1], y[2] - x[2]);
  }

 private:
  EdgeWeight weight_;
  const double *impulses_;
  std::vector<double> pos_;
};

} // namespace

double edge_weight(const ContactSystem &sys, EdgeWeight weight, const Vector *impulses, int c,
                   int from, const Vec3 &prev_dir)
{
  check_impulses(sys, weight, impulses);
  const Contact &k = sys.contacts()[c];
  return WalkWeight(sys, weight, impulses)(c, from, k.a == from ? k.b : k.a, prev_dir);
}

namespace {

// Algorithm 4 on a built graph (see Fibres).
Fibres greedy_fibres(const ContactSystem &sys, const ContactGraph &g, const WalkWeight &cost)
{
  const int nb = sys.num_bodies();
  std::vector<char> taken(nb, 0);

  // The smallest-weight contact from `cur` to an untaken body, ties to the smaller contact.
  auto step = [&](int cur, const Vec3 &prev_dir, int &next, int &via) {
    double best = 0;
    via = -1;
    for (int e = g.start[cur]; e < g.start[cur + 1]; ++e) {
      const int other = g.neighbour[e], c = g.contact[e];
      if (taken[other]) continue;
      const double w = cost(c, cur, other, prev_dir);
      if (via < 0 || w < best || (w == best && c < via)) {
        best = w;
        via = c;
        next = other;
      }
    }
    return via >= 0;
  };

  Fibres f;
  f.stats.num_contacts = g.num_edges;
  f.bodies.reserve(nb);
  f.contacts.reserve(nb);
  std::vector<int> back_bodies, back_contacts;
  for (int s = 0; s < nb; ++s) {
    int next = -1, via = -1;
    if (taken[s] || !step(s, Vec3::Zero(), next, via)) continue;
    // Forward from s, appended in place; the backward part is prepended afterwards.
    taken[s] = 1;
    const std::size_t body_base = f.bodies.size(), contact_base = f.contacts.size();
    f.bodies.push_back(s);
    int cur = s;
    Vec3 prev_dir = Vec3::Zero();
    do {
      taken[next] = 1;
      f.bodies.push_back(next);
      f.contacts.push_back(via);
      prev_dir = cost.direction(cur, next);
      cur = next;
    } while (step(cur, prev_dir, next, via));
    back_bodies.clear();
    back_contacts.clear();
    cur = s;
    prev_dir = cost.direction(s, f.bodies[body_base + 1]);
    while (step(cur, prev_dir, next, via)) {
      taken[next] = 1;
      back_bodies.push_back(next);
      back_contacts.push_back(via);
      prev_dir = cost.direction(cur, next);
      cur = next;
    }
    f.bodies.insert(f.bodies.begin() + body_base, back_bodies.rbegin(), back_bodies.rend());
    f.contacts.insert(f.contacts.begin() + contact_base, back_contacts.rbegin(),
                      back_contacts.rend());
    f.body_start.push_back(static_cast<int>(f.bodies.size()));
    f.contact_start.push_back(static_cast<int>(f.contacts.size()));
    const int len = static_cast<int>(f.contacts.size() - contact_base);
    if (static_cast<int>(f.stats.length_histogram.size()) <= len)
      f.stats.length_histogram.resize(len + 1, 0);
    ++f.stats.length_histogram[len];
  }
  f.stats.num_fibres = f.num_fibres();
  f.stats.contacts_in_fibres = static_cast<int>(f.contacts.size());
  return f;
}

} // namespace

Fibres build_fibres(const ContactSystem &sys, EdgeWeight weight, const Vector *impulses,
                    bool include_ghosts)
{
  check_impulses(sys, weight, impulses);
  return greedy_fibres(sys, contact_graph(sys, include_ghosts), WalkWeight(sys, weight, impulses));
}

namespace {

// Union-find with path halving.
struct DisjointSets {
  std::vector<int> up;
  explicit DisjointSets(int n) : up(n) { std::iota(up.begin(), up.end(), 0); }
  int find(int i)
  {
    while (up[i] != i) i = up[i] = up[up[i]];
    return i;
  }
  bool join(int a, int b)
  {
    a = find(a);
    b = find(b);
    if (a == b) return false;
    up[std::max(a, b)] = std::min(a, b);
    return true;
  }
};

} // namespace

Forest build_forest(const ContactSystem &sys, EdgeWeight weight, const Vector *impulses,
                    bool include_ghosts)
{
  check_impulses(sys, weight, impulses);
  const ContactGraph g = contact_graph(sys, include_ghosts);
  const WalkWeight cost(sys, weight, impulses);
  const Fibres fibres = greedy_fibres(sys, g, cost);
  const int nb = sys.num_bodies(), nc = sys.num_contacts();
  const int limit = include_ghosts ? nb : sys.num_owned_bodies();

  const int *pairs = sys.body_pairs();
  std::vector<char> in_tree(nc, 0);
  DisjointSets sets(nb);
  for (int c : fibres.contacts) {
    in_tree[c] = 1;
    sets.join(pairs[2 * std::size_t(c)], pairs[2 * std::size_t(c) + 1]);
  }
  // The remaining edges in contact order (a sequential pass), then sorted by (weight, contact).
  struct Edge {
    double w;
    int c, a, b;
    bool operator<(const Edge &o) const { return w < o.w || (w == o.w && c < o.c); }
  };
  std::vector<Edge> rest;
  rest.reserve(std::size_t(g.num_edges) - fibres.contacts.size());
  for (int c = 0; c < nc; ++c) {
    const int a = pairs[2 * std::size_t(c)], b = pairs[2 * std::size_t(c) + 1];
    if (b < 0 || a >= limit || b >= limit || in_tree[c]) continue;
    const int lo = std::min(a, b), hi = std::max(a, b);
    rest.push_back({cost.fixed(c, lo, hi), c, a, b});
  }
  std::sort(rest.begin(), rest.end());
  Forest f;
  f.num_edges = static_cast<int>(fibres.contacts.size());
  for (const Edge &e : rest)
    if (sets.join(e.a, e.b)) {
      in_tree[e.c] = 1;
      ++f.num_edges;
    }

  // Root every tree at its smallest body and list bodies in DFS post-order.
  f.parent.assign(nb, -1);
  f.parent_contact.assign(nb, -1);
  f.order.reserve(limit);
  f.stats.num_contacts = g.num_edges;
  f.stats.contacts_in_fibres = f.num_edges;
  std::vector<char> seen(nb, 0);
  std::vector<std::pair<int, int>> stack; // (body, next adjacency position)
  for (int root = 0; root < limit; ++root) {
    if (seen[root]) continue;
    seen[root] = 1;
    stack.emplace_back(root, g.start[root]);
    int tree_edges = 0;
    while (!stack.empty()) {
      auto &[i, e] = stack.back();
      if (e == g.start[i + 1]) {
        f.order.push_back(i);
        stack.pop_back();
        continue;
      }
      const int other = g.neighbour[e], c = g.contact[e];
      ++e;
      if (!in_tree[c] || seen[other]) continue;
      seen[other] = 1;
      f.parent[other] = i;
      f.parent_contact[other] = c;
      ++tree_edges;
      stack.emplace_back(other, g.start[other]);
    }
    if (tree_edges == 0) continue;
    ++f.stats.num_fibres;
    if (static_cast<int>(f.stats.length_histogram.size()) <= tree_edges)
      f.stats.length_histogram.resize(tree_edges + 1, 0);
    ++f.stats.length_histogram[tree_edges];
  }
  return f;
}

} // namespace fibre
