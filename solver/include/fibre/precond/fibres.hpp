// Fibres (thesis Algorithm 4) and spanning forests of the contact graph.
//
// Graph: bodies are nodes, body-body contacts are edges. A fibre is a chain of bodies, each
// in contact with the next; every body belongs to at most one fibre. The greedy walk follows
// the unmarked contact with the smallest edge weight.
#pragma once

#include <string>
#include <vector>

#include "fibre/core/names.hpp"
#include "fibre/core/system.hpp"

namespace fibre {

enum class EdgeWeight {
  z,        // |z_a - z_b| (thesis)
  straight, // misalignment with the previous edge of the chain (prefers straight chains)
  impulse,  // minus the last normal impulse (follows force chains)
};
template <> struct EnumNames<EdgeWeight> {
  static constexpr EnumName<EdgeWeight> table[] = {
      {EdgeWeight::z, "z"}, {EdgeWeight::straight, "straight"}, {EdgeWeight::impulse, "impulse"}};
};

struct FibreStats {
  int num_fibres = 0;
  int contacts_in_fibres = 0;
  int num_contacts = 0;              // body-body contacts considered
  std::vector<int> length_histogram; // [k] = number of fibres with k contacts
  double covered_fraction() const
  {
    return num_contacts > 0 ? double(contacts_in_fibres) / num_contacts : 0.0;
  }
};

// Body-body contacts as an undirected graph in CSR form: the neighbours of body i are
// neighbour[start[i] .. start[i+1]), reached through contact[...]. Wall contacts are not
// edges. Without ghosts, bodies >= num_owned_bodies() have no edges and contacts that touch
// them are left out.
struct ContactGraph {
  std::vector<int> start;     // num_bodies + 1
  std::vector<int> neighbour; // the other body
  std::vector<int> contact;   // the contact to it
  int num_edges = 0;          // body-body contacts in the graph
  int degree(int i) const { return start[i + 1] - start[i]; }
};
ContactGraph contact_graph(const ContactSystem &sys, bool include_ghosts);

// Fibres of Algorithm 4, concatenated. Fibre f has the bodies
// bodies[body_start[f] .. body_start[f+1]) in chain order and the contacts
// contacts[contact_start[f] .. contact_start[f+1]), contact k joining bodies k and k+1 of the
// fibre. Every fibre has at least two bodies. The position in these arrays is the fibre
// numbering.
//
// The greedy (deterministic; ties of the weight go to the smaller contact index): bodies are
// tried as start bodies in index order. An unmarked start body with an unmarked neighbour
// opens a fibre; the walk follows the smallest-weight contact to an unmarked neighbour until
// it is stuck, then walks on from the start body in the other direction (prepending), the
// first step there being compared against the first forward edge for `straight`.
//
// Maximal means, and the greedy guarantees: (i) no end body of a fibre touches a body that is
// in no fibre, so no fibre can be extended; (ii) no two bodies in no fibre touch, so no new
// fibre can be formed from uncovered bodies. (Algorithm 4 as printed only walks forward and
// can leave (i) violated at the start body.)
struct Fibres {
  std::vector<int> bodies;
  std::vector<int> body_start{0};
  std::vector<int> contacts;
  std::vector<int> contact_start{0};
  FibreStats stats;
  int num_fibres() const { return static_cast<int>(body_start.size()) - 1; }
  int length(int f) const { return contact_start[f + 1] - contact_start[f]; } // contacts
};

// Builds the fibres of `sys`. `impulses` (size num_contacts, normal impulse per contact) is
// read for EdgeWeight::impulse; without it that weight falls back to z. include_ghosts:
// whether chains may pass through ghost bodies (contact form yes, body form no).
Fibres build_fibres(const ContactSystem &sys, EdgeWeight weight, const Vector *impulses,
                    bool include_ghosts);

// Edge weight of contact c, walking from body `from` with the previous fibre edge arriving
// along `prev_dir` (zero vector: none). Exposed for the tests.
double edge_weight(const ContactSystem &sys, EdgeWeight weight, const Vector *impulses, int c,
                   int from, const Vec3 &prev_dir);

// Rooted spanning forest of the body graph: the fibres (built with the same weight), then the
// remaining body-body contacts joining two different trees in increasing order of a static
// weight (Kruskal; z for z and straight, -lambda_n for impulse; ties by contact index).
// order lists every body of the graph (ghosts only if included), children before their
// parent; parent[i] / parent_contact[i] are -1 for roots and for bodies outside the graph.
struct Forest {
  std::vector<int> order;
  std::vector<int> parent;
  std::vector<int> parent_contact;
  int num_edges = 0;
  FibreStats stats; // trees with at least one contact, read as fibres: count, sizes, coverage
};
Forest build_forest(const ContactSystem &sys, EdgeWeight weight, const Vector *impulses,
                    bool include_ghosts);

} // namespace fibre
