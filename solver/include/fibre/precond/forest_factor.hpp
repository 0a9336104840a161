// The block LDL^T factor of a matrix whose 6x6 block graph is a forest (the fibre, tree and
// block preconditioners of both forms), with its recycled storage.
#pragma once

#include <Eigen/Dense>
#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "fibre/core/system.hpp"
#include "fibre/precond/preconditioner.hpp"

namespace fibre::forest {

using RowMat6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;

constexpr int kB = 6;
constexpr int kPacked = 21; // lower triangle of a 6x6 block
constexpr int kBlock = 36;

// Packed lower triangle, column by column: (i, j), i >= j.
constexpr int at(int i, int j)
{
  return j * kB - j * (j - 1) / 2 + (i - j);
}

// ---- Recycled factor storage ----
//
// A preconditioner is rebuilt every time step with the same few megabytes of factors. Fresh
// pages cost a page fault per 4 KiB on first touch, about a third of the setup, so the arrays
// of destroyed factors are kept (per thread, at most kKeep of them) for the next setup.
class Storage {
 public:
  explicit Storage(std::size_t n = 0)
  {
    if (n == 0) return;
    if (Pool *pool = Pool::get()) {
      std::size_t best = pool->kept.size();
      for (std::size_t i = 0; i < pool->kept.size(); ++i)
        if (pool->kept[i].first >= n &&
            (best == pool->kept.size() || pool->kept[i].first < pool->kept[best].first))
          best = i;
      if (best < pool->kept.size()) {
        size_ = pool->kept[best].first;
        data_ = std::move(pool->kept[best].second);
        pool->kept.erase(pool->kept.begin() + static_cast<std::ptrdiff_t>(best));
        return;
      }
    }
    data_.reset(new double[n]);
    size_ = n;
  }
  Storage(Storage &&) = default;
  Storage &operator=(Storage &&other)
  {
    release();
    data_ = std::move(other.data_);
    size_ = other.size_;
    return *this;
  }
  ~Storage() { release(); }
  double *get() const { return data_.get(); }

 private:
  struct Pool {
    static constexpr std::size_t kKeep = 4;
    std::vector<std::pair<std::size_t, std::unique_ptr<double[]>>> kept;
    ~Pool() { closed() = true; }
    static bool &closed() // trivially destructible: still readable while statics die
    {
      thread_local bool flag = false;
      return flag;
    }
    static Pool *get()
    {
      if (closed()) return nullptr;
      thread_local Pool pool;
      return &pool;
    }
  };
  void release()
  {
    if (!data_) return;
    Pool *pool = Pool::get();
    if (!pool) return;
    if (pool->kept.size() == Pool::kKeep) { // keep the largest arrays
      std::size_t smallest = 0;
      for (std::size_t i = 1; i < pool->kept.size(); ++i)
        if (pool->kept[i].first < pool->kept[smallest].first) smallest = i;
      if (pool->kept[smallest].first >= size_) return;
      pool->kept.erase(pool->kept.begin() + static_cast<std::ptrdiff_t>(smallest));
    }
    pool->kept.emplace_back(size_, std::move(data_));
  }
  std::unique_ptr<double[]> data_;
  std::size_t size_ = 0;
};

// ---- Block LDL^T of a matrix whose block graph is a forest ----
//
// Nodes are 6x6 blocks, ordered so that every node comes before its parent (leaves first);
// eliminating in that order creates no fill. Node n holds D_n = sign_n L_n Delta_n L_n^T and
// the block B_n = A(n, parent), replaced by V_n = L_n^-1 B_n (row-major). A path of nodes is
// the block Thomas algorithm, isolated nodes are the block diagonal. With sign -1 nodes the
// same code eliminates the augmented (quasi-definite) system [-M -G^T; -G Sigma] of a contact
// tree: there every pivot keeps its sign, so no pivoting is needed.
class ForestFactor {
 public:
  // Two phases: set_node() for every node, then link(), then the values.
  ForestFactor(int nodes, int dim)
      : dim_(dim), parent_(nodes, -1), offset_(nodes, -1), wslot_(nodes, -1), sign_(nodes, 1),
        l_(std::size_t(kPacked) * nodes)
  {
  }
  int nodes() const { return static_cast<int>(parent_.size()); }
  // Node n: its `dim` entries start at `offset` in the vector (-1: an auxiliary unknown with
  // zero right-hand side whose value is dropped), `parent` > n or -1.
  void set_node(int n, int offset, int parent, int sign)
  {
    offset_[n] = offset;
    parent_[n] = parent;
    sign_[n] = static_cast<signed char>(sign);
  }
  // Coupling storage for the nodes with a parent only, in node order (the factorization
  // streams through it): setup cost is mostly first touch of fresh memory.
  void link()
  {
    int slots = 0;
    for (int n = 0; n < nodes(); ++n)
      if (parent_[n] >= 0) wslot_[n] = slots++;
    w_ = Storage(std::size_t(kBlock) * slots);
  }
  // Packed lower triangle of sign_n D_n, to be filled in place.
  double *diag_data(int n) { return l_.get() + std::size_t(kPacked) * n; }
  void set_diag(int n, const Vec6 &diagonal)
  {
    double *l = diag_data(n);
    for (int k = 0; k < kPacked; ++k) l[k] = 0.0;
    for (int i = 0; i < kB; ++i) l[at(i, i)] = diagonal[i];
  }
  // Row-major B_n, to be filled in place.
  double *coupling_data(int n) { return w_.get() + std::size_t(kBlock) * wslot_[n]; }
  // B_n = A(n, parent), for a node with a parent.
  Eigen::Map<RowMat6> coupling(int n) { return Eigen::Map<RowMat6>(coupling_data(n)); }

  // The factorization, in node order (every node before its parent).
  void factor();
  // z = A_forest^-1 r on the nodes' entries; other entries of z are left untouched.
  void solve(const Vector &r, Vector &z, std::vector<double> &work) const;

 private:
  int dim_;
  std::vector<int> parent_;
  std::vector<int> offset_;
  std::vector<int> wslot_; // position in w_, -1 for roots
  std::vector<signed char> sign_;
  Storage l_; // 21 per node: sign D, then its L Delta L^T factor
  Storage w_; // 36 per node with a parent: B, then V = L^-1 B
};

// The preconditioner z = A_forest^-1 r of a forest factor, after factoring it; covers_all: every
// entry of a vector of `size` belongs to a node (false: ghost bodies, left zero).
std::unique_ptr<Preconditioner> finish(const char *name, ForestFactor f, Eigen::Index size,
                                       bool covers_all);
// z = D^-1 r with D a positive diagonal, given inverted.
std::unique_ptr<Preconditioner> diagonal(Vector inv_diag);

} // namespace fibre::forest
