// Fibres (thesis Algorithm 4) and spanning forests of the contact graph.
//
// Graph: bodies are nodes, body-body contacts are edges. A fibre is a chain of bodies, each
// in contact with the next; every body belongs to at most one fibre. The greedy walk follows
// the unmarked contact with the smallest edge weight.
#pragma once

#include <string>
#include <vector>

#include "fibre/system.hpp"

namespace fibre {

enum class EdgeWeight {
  z,         // |z_a - z_b| (thesis)
  straight,  // misalignment with the previous edge of the chain (prefers straight chains)
  impulse,   // minus the last normal impulse (follows force chains)
};
const char *to_string(EdgeWeight w);
bool parse_weight(const std::string &s, EdgeWeight &w);

struct FibreStats {
  int num_fibres = 0;
  int contacts_in_fibres = 0;
  int num_contacts = 0;            // body-body contacts considered
  std::vector<int> length_histogram;  // [k] = number of fibres with k contacts
  double covered_fraction() const
  {
    return num_contacts > 0 ? double(contacts_in_fibres) / num_contacts : 0.0;
  }
};

}  // namespace fibre
