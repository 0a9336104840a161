// fibre::Exchange on LAMMPS halo communication (see lammps_exchange.h).
#include "lammps_exchange.h"

#include <algorithm>
#include <map>
#include <string>
#include <unordered_map>

#include "atom.h"
#include "comm.h"
#include "fix.h"
#include "host.h"
#include "lammps.h"

namespace fibre_lmp {

// The sweeps' halo (fibre::Exchange::Halo) by MPI point to point, on the bodies that contacts
// move. LAMMPS's forward and reverse comms carry 6 values for every ghost atom through every
// swap; a sweep on a stiff pile needs only the few dozen bodies that straddle a boundary, and
// two LAMMPS comms a sweep cost as much as the sweep itself (bench/README.md, "The sweeps'
// halo").
class PointHalo final : public fibre::Exchange::Halo {
 public:
  struct Link {
    int rank;
    std::vector<int> bodies; // in the order of the ghosts' list on the ghosts' process
  };
  PointHalo(MPI_Comm comm, std::vector<Link> ghosts, std::vector<Link> shared,
            std::vector<std::pair<int, int>> images, int colours = 1, int colour = 0)
      : comm_(comm), ghosts_(std::move(ghosts)), shared_(std::move(shared)),
        images_(std::move(images)), colours_(colours), colour_(colour)
  {
    for (const std::vector<Link> *links : {&ghosts_, &shared_})
      for (const Link &l : *links) bodies_.insert(bodies_.end(), l.bodies.begin(), l.bodies.end());
    for (const auto &[image, body] : images_) {
      bodies_.push_back(image);
      bodies_.push_back(body);
    }
    std::sort(bodies_.begin(), bodies_.end());
    bodies_.erase(std::unique(bodies_.begin(), bodies_.end()), bodies_.end());
  }
  int colours() const override { return colours_; }
  int colour() const override { return colour_; }
  const std::vector<int> *bodies() const override { return &bodies_; }

  // The ghosts' values added into their owners' (images' into their bodies'), the ghosts' and
  // images' then zero: Exchange::reverse_sum where every ghost body is in the links.
  void reverse_sum(fibre::Vector &v) const
  {
    move(v, ghosts_, shared_, true, kChanges);
    for (const auto &[image, body] : images_) v.segment<6>(6 * body) += v.segment<6>(6 * image);
    for (const Link &l : ghosts_)
      for (const int b : l.bodies) v.segment<6>(6 * b).setZero();
    for (const auto &[image, body] : images_) v.segment<6>(6 * image).setZero();
  }

  void sum_copies(fibre::Vector &v) const override
  {
    move(v, ghosts_, shared_, true, kChanges); // the ghosts' values into their owners
    for (const auto &[image, body] : images_) v.segment<6>(6 * body) += v.segment<6>(6 * image);
    move(v, shared_, ghosts_, false, kTotals); // the owners' sums back to the ghosts
    for (const auto &[image, body] : images_) v.segment<6>(6 * image) = v.segment<6>(6 * body);
  }

 private:
  static constexpr int kChanges = 1, kTotals = 2;

  static std::size_t values(const std::vector<Link> &links)
  {
    std::size_t n = 0;
    for (const Link &l : links) n += 6 * l.bodies.size();
    return n;
  }

  // Sends the bodies of `from` to their links' processes and receives those of `to`, adding
  // (in ascending rank order, so that a sum does not depend on the messages' arrival) or
  // copying them into v.
  void move(fibre::Vector &v, const std::vector<Link> &from, const std::vector<Link> &to, bool add,
            int tag) const
  {
    in_.resize(values(to));
    out_.resize(values(from));
    requests_.clear();
    std::size_t at = 0;
    for (const Link &l : to) {
      requests_.emplace_back();
      MPI_Irecv(in_.data() + at, static_cast<int>(6 * l.bodies.size()), MPI_DOUBLE, l.rank, tag,
                comm_, &requests_.back());
      at += 6 * l.bodies.size();
    }
    at = 0;
    for (const Link &l : from) {
      const std::size_t first = at;
      for (const int b : l.bodies)
        for (int d = 0; d < 6; ++d) out_[at++] = v[6 * Eigen::Index(b) + d];
      requests_.emplace_back();
      MPI_Isend(out_.data() + first, static_cast<int>(at - first), MPI_DOUBLE, l.rank, tag, comm_,
                &requests_.back());
    }
    MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
    at = 0;
    for (const Link &l : to)
      for (const int b : l.bodies)
        for (int d = 0; d < 6; ++d, ++at) {
          double &x = v[6 * Eigen::Index(b) + d];
          x = add ? x + in_[at] : in_[at];
        }
  }

  MPI_Comm comm_;
  std::vector<Link> ghosts_; // per owner process, ascending: the touched ghosts it owns
  std::vector<Link> shared_; // per process, ascending: the owned bodies it touches as ghosts
  std::vector<std::pair<int, int>> images_; // touched periodic images here, and their bodies
  std::vector<int> bodies_;                 // every body above, once, ascending
  int colours_, colour_;
  mutable std::vector<double> in_, out_;
  mutable std::vector<MPI_Request> requests_;
};

namespace {

// Two colours for the processes (Exchange::Halo::colours), the same on every one: each owner
// lists, per pair of processes that touch one of its bodies, how many such bodies; the lists
// are gathered, and each process in rank order takes the colour whose processes of lower rank
// share the fewest bodies with it. Processes that share bodies and a colour remain where the
// graph is not two-colourable (a 2 x 2 grid's diagonal neighbours, at the corner's few
// bodies); the sweeps split those bodies' masses among them.
std::pair<int, int> colour_processes(MPI_Comm comm, int nprocs, int me,
                                     const std::vector<int> &local_edges)
{
  const int n_local = static_cast<int>(local_edges.size());
  std::vector<int> counts(nprocs), displs(nprocs, 0);
  MPI_Allgather(&n_local, 1, MPI_INT, counts.data(), 1, MPI_INT, comm);
  for (int r = 1; r < nprocs; ++r) displs[r] = displs[r - 1] + counts[r - 1];
  std::vector<int> edges(std::size_t(displs[nprocs - 1] + counts[nprocs - 1]));
  MPI_Allgatherv(local_edges.data(), n_local, MPI_INT, edges.data(), counts.data(), displs.data(),
                 MPI_INT, comm);
  if (edges.empty()) return {1, 0};
  // (a, b, bodies) triples, a < b: each process's weights to its neighbours of lower rank
  std::vector<std::vector<std::pair<int, long>>> lower(nprocs);
  for (std::size_t e = 0; e + 2 < edges.size(); e += 3)
    lower[edges[e + 1]].emplace_back(edges[e], edges[e + 2]);
  std::vector<int> colour(nprocs, 0);
  for (int r = 0; r < nprocs; ++r) {
    long shared[2] = {0, 0};
    for (const auto &[q, bodies] : lower[r]) shared[colour[q]] += bodies;
    colour[r] = shared[1] < shared[0] ? 1 : 0;
  }
  return {2, colour[me]};
}

} // namespace

LammpsExchange::LammpsExchange(LAMMPS_NS::LAMMPS *lmp, LAMMPS_NS::Fix *fix, MPI_Comm world)
    : lmp_(lmp), fix_(fix), world_(world)
{
  MPI_Comm_dup(world, &halo_comm_);
}

LammpsExchange::~LammpsExchange()
{
  every_ghost_.reset();
  if (halo_comm_ != MPI_COMM_NULL) MPI_Comm_free(&halo_comm_);
}

const std::vector<int> &LammpsExchange::ghost_owners() const
{
  // A forward comm: every process refreshes when any one must (a process whose atoms were not
  // rebuilt keeps its owners, but the others' comm needs it; deciding alone deadlocked).
  int known = ghost_owners_known_ ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &known, 1, MPI_INT, MPI_MIN, halo_comm_);
  if (known) return ghost_owners_;
  resize_halo();
  const int nlocal = lmp_->atom->nlocal;
  for (int i = 0; i < nlocal; ++i) halo_[std::size_t(kValuesPerAtom) * i] = lmp_->comm->me;
  fibre_forward_comm(lmp_->comm, fix_, kValuesPerAtom);
  ghost_owners_.assign(body_atom_.size(), -1);
  for (std::size_t k = num_owned_; k < body_atom_.size(); ++k)
    ghost_owners_[k] = static_cast<int>(halo_[std::size_t(kValuesPerAtom) * body_atom_[k]]);
  ghost_owners_known_ = true;
  return ghost_owners_;
}

namespace {

// Per pair of processes that touch a body owned here (this one too where it touches it), how
// many such bodies: (rank, rank, count) triples, the edges of the process colouring.
std::vector<int> process_edges(const std::vector<char> &touched,
                               const std::vector<PointHalo::Link> &shared, int num_owned, int me)
{
  std::vector<std::vector<int>> touching(num_owned);
  for (int k = 0; k < num_owned; ++k)
    if (touched[k]) touching[k].push_back(me);
  for (const PointHalo::Link &l : shared)
    for (const int k : l.bodies)
      if (touching[k].empty() || touching[k].back() != l.rank) touching[k].push_back(l.rank);
  std::map<std::pair<int, int>, int> pairs;
  for (const std::vector<int> &ranks : touching)
    for (std::size_t i = 0; i < ranks.size(); ++i)
      for (std::size_t j = i + 1; j < ranks.size(); ++j)
        ++pairs[{std::min(ranks[i], ranks[j]), std::max(ranks[i], ranks[j])}];
  std::vector<int> edges;
  for (const auto &[ranks, bodies] : pairs) {
    edges.push_back(ranks.first);
    edges.push_back(ranks.second);
    edges.push_back(bodies);
  }
  return edges;
}

} // namespace

std::unique_ptr<fibre::Exchange::Halo> LammpsExchange::halo(const std::vector<char> &touched,
                                                            bool colour) const
{
  return point_halo(touched, colour);
}

std::unique_ptr<PointHalo> LammpsExchange::point_halo(const std::vector<char> &touched,
                                                      bool colour) const
{
  using Link = PointHalo::Link;
  const int nprocs = lmp_->comm->nprocs, me = lmp_->comm->me;
  const int nbody = static_cast<int>(body_atom_.size());
  std::vector<std::pair<int, int>> images;
  for (int k = num_owned_; k < nbody; ++k)
    if (touched[k] && local_owners_[k] != k) images.emplace_back(k, local_owners_[k]);
  if (nprocs == 1)
    return std::make_unique<PointHalo>(halo_comm_, std::vector<Link>(), std::vector<Link>(),
                                       std::move(images));

  // the touched ghosts by owner, and to each owner their tags
  const std::vector<int> &owner = ghost_owners();
  std::vector<std::vector<int>> ghosts_of(nprocs);
  for (int k = num_owned_; k < nbody; ++k)
    if (touched[k] && local_owners_[k] == k) ghosts_of[owner[k]].push_back(k);
  std::vector<int> send_count(nprocs), recv_count(nprocs);
  for (int r = 0; r < nprocs; ++r) send_count[r] = static_cast<int>(ghosts_of[r].size());
  MPI_Alltoall(send_count.data(), 1, MPI_INT, recv_count.data(), 1, MPI_INT, halo_comm_);
  const LAMMPS_NS::tagint *tag = lmp_->atom->tag;
  std::vector<std::vector<double>> tags_out(nprocs), tags_in(nprocs);
  std::vector<MPI_Request> requests;
  for (int r = 0; r < nprocs; ++r)
    if (recv_count[r] > 0) {
      tags_in[r].resize(recv_count[r]);
      requests.emplace_back();
      MPI_Irecv(tags_in[r].data(), recv_count[r], MPI_DOUBLE, r, 0, halo_comm_, &requests.back());
    }
  for (int r = 0; r < nprocs; ++r)
    if (send_count[r] > 0) {
      for (const int k : ghosts_of[r])
        tags_out[r].push_back(static_cast<double>(tag[body_atom_[k]]));
      requests.emplace_back();
      MPI_Isend(tags_out[r].data(), send_count[r], MPI_DOUBLE, r, 0, halo_comm_, &requests.back());
    }
  MPI_Waitall(static_cast<int>(requests.size()), requests.data(), MPI_STATUSES_IGNORE);

  std::vector<Link> ghosts, shared;
  for (int r = 0; r < nprocs; ++r)
    if (send_count[r] > 0) ghosts.push_back({r, std::move(ghosts_of[r])});
  for (int r = 0; r < nprocs; ++r) {
    if (recv_count[r] == 0) continue;
    Link link{r, {}};
    for (const double t : tags_in[r]) {
      const auto it = owned_body_.find(static_cast<LAMMPS_NS::tagint>(t));
      if (it == owned_body_.end()) {
        const std::string msg = "fix fibre_contact: process " + std::to_string(r) +
                                " holds a ghost of atom " + std::to_string(long(t)) +
                                ", which process " + std::to_string(me) + " does not own";
        fail_one(lmp_->error, FLERR, msg);
      }
      link.bodies.push_back(it->second);
    }
    shared.push_back(std::move(link));
  }
  if (!colour)
    return std::make_unique<PointHalo>(halo_comm_, std::move(ghosts), std::move(shared),
                                       std::move(images));
  const std::vector<int> edges = process_edges(touched, shared, num_owned_, me);
  const auto [colours, mine] = colour_processes(halo_comm_, nprocs, me, edges);
  return std::make_unique<PointHalo>(halo_comm_, std::move(ghosts), std::move(shared),
                                     std::move(images), colours, mine);
}

void LammpsExchange::set_bodies(const std::vector<int> &body_atom, int num_owned)
{
  body_atom_ = body_atom;
  num_owned_ = num_owned;
  has_halo_ = lmp_->comm->nprocs > 1 || body_atom.size() > std::size_t(num_owned);
  // a ghost with the tag of an owned body is its periodic image on this process; without
  // ghosts and other processes no tag is looked up (the map took 33 bytes a sphere)
  const LAMMPS_NS::tagint *tag = lmp_->atom->tag;
  std::unordered_map<LAMMPS_NS::tagint, int>().swap(owned_body_);
  if (has_halo_)
    for (int k = 0; k < num_owned; ++k) owned_body_.emplace(tag[body_atom[k]], k);
  local_owners_.resize(body_atom.size());
  for (int k = 0; k < static_cast<int>(body_atom.size()); ++k) {
    const auto it = k < num_owned ? owned_body_.end() : owned_body_.find(tag[body_atom[k]]);
    local_owners_[k] = it == owned_body_.end() ? k : it->second;
  }
  ghost_owners_known_ = false;
  every_ghost_.reset();
}

bool LammpsExchange::comm_tiled() const
{
#ifdef FIBRE_HOST_LIGGGHTS
  return false;
#else
  return lmp_->comm->style != 0;
#endif
}

void LammpsExchange::resize_halo() const
{
  const std::size_t nall = std::size_t(lmp_->atom->nlocal + lmp_->atom->nghost);
  if (halo_.size() < kValuesPerAtom * nall) halo_.resize(kValuesPerAtom * nall);
}

void LammpsExchange::forward(fibre::Vector &body_vec) const
{
  if (!has_halo_) return;
  resize_halo();
  const int nbody = static_cast<int>(body_atom_.size());
  for (int k = 0; k < num_owned_; ++k) {
    double *dst = &halo_[std::size_t(kValuesPerAtom) * body_atom_[k]];
    for (int d = 0; d < kValuesPerAtom; ++d) dst[d] = body_vec[kValuesPerAtom * k + d];
  }
  fibre_forward_comm(lmp_->comm, fix_, kValuesPerAtom);
  for (int k = num_owned_; k < nbody; ++k) {
    const double *src = &halo_[std::size_t(kValuesPerAtom) * body_atom_[k]];
    for (int d = 0; d < kValuesPerAtom; ++d) body_vec[kValuesPerAtom * k + d] = src[d];
  }
}

void LammpsExchange::reverse_sum(fibre::Vector &body_vec) const
{
  if (!has_halo_) return;
  if (comm_tiled()) {
    // LAMMPS 29 Sep 2021's CommTiled has no variable-size reverse comm: point to point over
    // every ghost body, the sweeps' halo with all of them touched.
    if (!every_ghost_) every_ghost_ = point_halo(std::vector<char>(body_atom_.size(), 1), false);
    every_ghost_->reverse_sum(body_vec);
    return;
  }
  resize_halo();
  const std::size_t nall = std::size_t(lmp_->atom->nlocal + lmp_->atom->nghost);
  std::fill(halo_.begin(), halo_.begin() + kValuesPerAtom * nall, 0.0);
  const int nbody = static_cast<int>(body_atom_.size());
  for (int k = num_owned_; k < nbody; ++k) {
    double *dst = &halo_[std::size_t(kValuesPerAtom) * body_atom_[k]];
    for (int d = 0; d < kValuesPerAtom; ++d) {
      dst[d] = body_vec[kValuesPerAtom * k + d];
      body_vec[kValuesPerAtom * k + d] = 0.0;
    }
  }
  fibre_reverse_comm(lmp_->comm, fix_, kValuesPerAtom);
  for (int k = 0; k < num_owned_; ++k) {
    const double *src = &halo_[std::size_t(kValuesPerAtom) * body_atom_[k]];
    for (int d = 0; d < kValuesPerAtom; ++d) body_vec[kValuesPerAtom * k + d] += src[d];
  }
}

void LammpsExchange::sum(double *values, int n) const
{
  if (n > 0) MPI_Allreduce(MPI_IN_PLACE, values, n, MPI_DOUBLE, MPI_SUM, world_);
}

void LammpsExchange::max(double *values, int n) const
{
  if (n > 0) MPI_Allreduce(MPI_IN_PLACE, values, n, MPI_DOUBLE, MPI_MAX, world_);
}

long LammpsExchange::exclusive_prefix_sum(long local) const
{
  long result = 0;
  MPI_Exscan(&local, &result, 1, MPI_LONG, MPI_SUM, world_);
  int rank = 0;
  MPI_Comm_rank(world_, &rank);
  return rank == 0 ? 0 : result; // MPI_Exscan leaves rank 0's result undefined
}

int LammpsExchange::pack_forward(int n, const int *list, double *buf) const
{
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const double *src = &halo_[std::size_t(kValuesPerAtom) * list[i]];
    for (int d = 0; d < kValuesPerAtom; ++d) buf[m++] = src[d];
  }
  return m;
}

void LammpsExchange::unpack_forward(int first, int n, const double *buf) const
{
  resize_halo();
  int m = 0;
  for (int i = first; i < first + n; ++i) {
    double *dst = &halo_[std::size_t(kValuesPerAtom) * i];
    for (int d = 0; d < kValuesPerAtom; ++d) dst[d] = buf[m++];
  }
}

int LammpsExchange::pack_reverse(int first, int n, double *buf) const
{
  int m = 0;
  for (int i = first; i < first + n; ++i) {
    const double *src = &halo_[std::size_t(kValuesPerAtom) * i];
    for (int d = 0; d < kValuesPerAtom; ++d) buf[m++] = src[d];
  }
  return m;
}

void LammpsExchange::unpack_reverse(int n, const int *list, const double *buf) const
{
  int m = 0;
  for (int i = 0; i < n; ++i) {
    double *dst = &halo_[std::size_t(kValuesPerAtom) * list[i]];
    for (int d = 0; d < kValuesPerAtom; ++d) dst[d] += buf[m++];
  }
}

} // namespace fibre_lmp
