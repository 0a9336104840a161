// Every preconditioner in both forms against a dense reference assembled from the thesis
// formula (reference.hpp): P^-1 is symmetric positive definite and equals the dense inverse of
// the matrix it claims to invert.
#include <gtest/gtest.h>

#include <set>

#include "fibre/precond/preconditioner_family.hpp"
#include "fibre/scenes.hpp"
#include "reference.hpp"

using namespace fibre;
using test::Dense;

namespace {

const PrecondKind kKinds[] = {PrecondKind::none, PrecondKind::jacobi, PrecondKind::block,
                              PrecondKind::fibre, PrecondKind::tree};
const EdgeWeight kWeights[] = {EdgeWeight::z, EdgeWeight::straight, EdgeWeight::impulse};

ContactSystem with_ghosts(const ContactSystem &sys, int ghosts)
{
  return ContactSystem(sys.bodies(), sys.contacts(), sys.rows(), sys.params(),
                       sys.num_bodies() - ghosts);
}

// Unknowns of a form: all contact rows, or the owned bodies' 6 entries.
Eigen::Index unknowns(Form form, const ContactSystem &sys)
{
  return form == Form::contact ? sys.contact_dofs()
                               : Eigen::Index(kBodyDofs) * sys.num_owned_bodies();
}

// The dense matrix of P^-1 on the unknowns, column by column from unit vectors. Entries of
// ghosts must come back zero.
Dense dense_inverse(Form form, const ContactSystem &sys, const Preconditioner &P)
{
  const Eigen::Index size = form == Form::contact ? sys.contact_dofs() : sys.body_dofs();
  const Eigen::Index n = unknowns(form, sys);
  Dense Z(n, n);
  for (Eigen::Index j = 0; j < n; ++j) {
    Vector e = Vector::Zero(size), z;
    e[j] = 1.0;
    P.apply(e, z);
    EXPECT_EQ(z.size(), size);
    EXPECT_EQ(z.tail(size - n).norm(), 0.0);
    Z.col(j) = z.head(n);
  }
  return Z;
}

void expect_spd(const Dense &Z, const std::string &what)
{
  const double scale = Z.norm();
  EXPECT_LT((Z - Z.transpose()).norm(), 1e-10 * scale) << what;
  // Positive definite: the Cholesky factorization of the symmetric part exists.
  const Eigen::LLT<Dense> llt(0.5 * (Z + Z.transpose()));
  EXPECT_EQ(llt.info(), Eigen::Success) << what;
}

// Keeps the entries (i, j) of A whose blocks (of `bs` rows) satisfy keep(bi, bj); diagonal
// blocks are always kept.
template <class Keep> Dense block_pattern(const Dense &A, int bs, Keep keep)
{
  const int nblocks = static_cast<int>(A.rows() / bs);
  Dense P = Dense::Zero(A.rows(), A.cols());
  for (int bi = 0; bi < nblocks; ++bi)
    for (int bj = 0; bj < nblocks; ++bj)
      if (bi == bj || keep(bi, bj))
        P.block(bs * bi, bs * bj, bs, bs) = A.block(bs * bi, bs * bj, bs, bs);
  return P;
}

// The matrix each preconditioner claims to invert, from the dense A or K alone (and the
// fibres/forest, which define its pattern).
Dense reference_matrix(Form form, const ContactSystem &sys, const PrecondOptions &opt)
{
  const int rows = sys.rows(), owned = sys.num_owned_bodies();
  if (form == Form::contact) {
    const Dense A = test::dense_A(sys);
    switch (opt.kind) {
    case PrecondKind::none:
      return Dense::Identity(A.rows(), A.cols());
    case PrecondKind::jacobi:
      return Dense(A.diagonal().asDiagonal());
    case PrecondKind::block:
      return block_pattern(A, rows, [](int, int) { return false; });
    case PrecondKind::fibre: {
      // Principal submatrix on the fibre contacts.
      std::vector<char> in(sys.num_contacts(), 0);
      for (int c : build_fibres(sys, opt.weight, opt.impulses, true).contacts) in[c] = 1;
      return block_pattern(A, rows, [&](int c, int d) { return in[c] && in[d]; });
    }
    case PrecondKind::tree: {
      // Principal submatrix on the forest contacts and all wall contacts.
      const Forest t = build_forest(sys, opt.weight, opt.impulses, true);
      std::vector<char> in(sys.num_contacts(), 0);
      for (int c : t.parent_contact)
        if (c >= 0) in[c] = 1;
      for (int c = 0; c < sys.num_contacts(); ++c)
        if (sys.contacts()[c].is_wall()) in[c] = 1;
      return block_pattern(A, rows, [&](int c, int d) { return in[c] && in[d]; });
    }
    }
  }
  const Eigen::Index n = Eigen::Index(kBodyDofs) * owned;
  const Dense K = test::dense_K(sys).topLeftCorner(n, n);
  switch (opt.kind) {
  case PrecondKind::none:
    return Dense::Identity(n, n);
  case PrecondKind::jacobi:
    return Dense(K.diagonal().asDiagonal());
  case PrecondKind::block:
    return block_pattern(K, 6, [](int, int) { return false; });
  case PrecondKind::fibre: {
    // K on chain neighbours only.
    const Fibres f = build_fibres(sys, opt.weight, opt.impulses, false);
    std::set<std::pair<int, int>> links;
    for (int k = 0; k < f.num_fibres(); ++k)
      for (int p = f.body_start[k]; p + 1 < f.body_start[k + 1]; ++p) {
        links.insert({f.bodies[p], f.bodies[p + 1]});
        links.insert({f.bodies[p + 1], f.bodies[p]});
      }
    return block_pattern(K, 6, [&](int i, int j) { return links.count({i, j}) > 0; });
  }
  case PrecondKind::tree: {
    // K on the forest's edges only.
    const Forest t = build_forest(sys, opt.weight, opt.impulses, false);
    return block_pattern(K, 6, [&](int i, int j) { return t.parent[i] == j || t.parent[j] == i; });
  }
  }
  return Dense();
}

void expect_matches_reference(Form form, const ContactSystem &sys, const PrecondOptions &opt,
                              double tol, bool coupled)
{
  const std::string what =
      std::string(to_string(form)) + " " + to_string(opt.kind) + " " + to_string(opt.weight);
  FibreStats stats;
  const auto P = make_preconditioner(form, sys, serial_exchange(), opt, &stats);
  const Dense Z = dense_inverse(form, sys, *P);
  expect_spd(Z, what);
  const Dense R = reference_matrix(form, sys, opt);
  // Z R = I, measured as a relative difference of Z against R^-1.
  const Dense Rinv = R.llt().solve(Dense::Identity(R.rows(), R.cols()));
  EXPECT_LT((Z - Rinv).norm(), tol * Rinv.norm()) << what;
  if (coupled && (opt.kind == PrecondKind::fibre || opt.kind == PrecondKind::tree)) {
    // The pattern is not trivial: more than the block diagonal is inverted.
    EXPECT_GT(stats.contacts_in_fibres, 0) << what;
    PrecondOptions block = opt;
    block.kind = PrecondKind::block;
    EXPECT_GT(
        (Rinv - dense_inverse(form, sys, *make_preconditioner(form, sys, serial_exchange(), block)))
            .norm(),
        1e-3 * Rinv.norm())
        << what;
  }
}

// coupled: the scene has fibres of two contacts or more, so fibre and tree differ from block.
void expect_all(const ContactSystem &sys, double tol = 1e-9, bool coupled = true)
{
  const Vector impulses = Vector::LinSpaced(sys.num_contacts(), 0.0, 1.0).reverse();
  for (Form form : {Form::contact, Form::body})
    for (PrecondKind kind : kKinds) {
      PrecondOptions opt;
      opt.kind = kind;
      opt.impulses = &impulses;
      const bool structured = kind == PrecondKind::fibre || kind == PrecondKind::tree;
      for (EdgeWeight w : kWeights) {
        if (!structured && w != EdgeWeight::z) continue;
        opt.weight = w;
        expect_matches_reference(form, sys, opt, tol, coupled || form == Form::body);
      }
    }
}

} // namespace

TEST(Preconditioners, Names)
{
  for (PrecondKind k : kKinds) {
    PrecondKind back = PrecondKind::none;
    ASSERT_TRUE(parse(to_string(k), back));
    EXPECT_EQ(back, k);
  }
  PrecondKind k;
  EXPECT_FALSE(parse("ilu", k));
}

TEST(Preconditioners, Grid)
{
  expect_all(grid_scene(SceneParams{}));
}

TEST(Preconditioners, PilesWithWalls)
{
  for (std::uint64_t seed : {1u, 2u}) {
    SceneParams p;
    p.seed = seed;
    expect_all(pile_scene(50, p));
  }
}

TEST(Preconditioners, TranslationalRowsOnly)
{
  SceneParams p;
  p.rows = 3;
  expect_all(pile_scene(60, p));
}

TEST(Preconditioners, MaskedRows)
{
  ContactSystem sys = pile_scene(40, SceneParams{});
  std::vector<unsigned char> mask(sys.contact_dofs(), 1);
  for (std::size_t i = 1; i < mask.size(); i += 5) mask[i] = 0;
  for (int r = 0; r < 6; ++r) mask[6 * 3 + r] = 0; // a whole contact released
  sys.set_row_mask(mask);
  expect_all(sys);
}

// Ghost bodies: body-form chains and trees avoid them and give them zero; contact-form
// chains may pass through them (their coupling blocks are local and exact).
TEST(Preconditioners, Ghosts)
{
  const ContactSystem sys = with_ghosts(pile_scene(60, SceneParams{}), 15);
  expect_all(sys);
  const Fibres f = build_fibres(sys, EdgeWeight::z, nullptr, true);
  bool through_ghost = false;
  for (int i : f.bodies) through_ghost |= i >= sys.num_owned_bodies();
  EXPECT_TRUE(through_ghost);
}

// Tiny Sigma (stiff contacts): the tree's augmented elimination pivots on Sigma for the wall
// contacts and must stay accurate. Sigma / ||A|| reaches 1e-12 here; with 3 rows, where a
// wall pins only 3 of a body's 6 directions, round-off grows like eps ||A|| / Sigma (as for any
// factorization of A), so that case stops at Sigma / ||A|| ~ 1e-8 (the thesis's t).
TEST(Preconditioners, StiffContacts)
{
  for (double eps : {1e-12, 1e-16}) {
    SceneParams p;
    p.compliance = eps;
    expect_all(pile_scene(40, p), 1e-7);
  }
  SceneParams p;
  p.compliance = 1e-12;
  p.rows = 3;
  expect_all(pile_scene(40, p), 1e-7);
}

// A halo on one process: ghost g is a copy of owned body owner[g]. It stands in for a
// neighbour process that holds some of an owned body's contacts.
class CopyExchange final : public Exchange {
 public:
  explicit CopyExchange(std::vector<int> owner) : owner_(std::move(owner)) {}
  void forward(Vector &v) const override
  {
    for (std::size_t g = 0; g < owner_.size(); ++g)
      if (owner_[g] >= 0) v.segment<6>(6 * g) = v.segment<6>(6 * owner_[g]);
  }
  void reverse_sum(Vector &v) const override
  {
    for (std::size_t g = 0; g < owner_.size(); ++g)
      if (owner_[g] >= 0) {
        v.segment<6>(6 * owner_[g]) += v.segment<6>(6 * g);
        v.segment<6>(6 * g).setZero();
      }
  }
  void sum(double *, int) const override {}
  void max(double *, int) const override {}
  long exclusive_prefix_sum(long) const override { return 0; }

 private:
  std::vector<int> owner_; // per body: its owner if a ghost, else -1
};

// Body form: the diagonal blocks of K gather the contacts held on ghost copies, so the
// preconditioners equal those of the same system with every contact on the owners.
TEST(Preconditioners, HaloCompletesBodyBlocks)
{
  const ContactSystem whole = pile_scene(50, SceneParams{});
  const int n = whole.num_bodies();
  std::vector<Body> bodies = whole.bodies();
  std::vector<Contact> contacts = whole.contacts();
  std::vector<int> owner(n, -1);
  // Every third contact sees its body a through a ghost copy.
  for (std::size_t c = 0; c < contacts.size(); c += 3) {
    const int a = contacts[c].a;
    bodies.push_back(bodies[a]);
    owner.push_back(a);
    contacts[c].a = static_cast<int>(bodies.size()) - 1;
  }
  ContactSystem split(bodies, contacts, 6, whole.params(), n);
  split.set_rhs(whole.rhs());
  const CopyExchange ex(owner);
  { // the fake halo reproduces the whole system's K
    const Vector v = Vector::Random(whole.body_dofs());
    Vector vs = Vector::Zero(split.body_dofs()), kv, kvs;
    vs.head(v.size()) = v;
    BodySpaceOperator(whole, serial_exchange()).apply(v, kv);
    BodySpaceOperator(split, ex).apply(vs, kvs);
    ASSERT_LT((kvs.head(kv.size()) - kv).norm(), 1e-12 * kv.norm());
  }
  const Eigen::Index nd = 6 * Eigen::Index(n);
  const Dense K = test::dense_K(whole);
  for (PrecondKind kind : kKinds) {
    PrecondOptions opt;
    opt.kind = kind;
    const auto P = make_preconditioner(Form::body, split, ex, opt);
    const Dense Z = dense_inverse(Form::body, split, *P);
    // The reference pattern comes from the split system's own fibres and forest (contacts
    // through ghosts are no chain links), the values from the whole K.
    Dense R = reference_matrix(Form::body, split, opt);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        if (kind != PrecondKind::none && (i == j || R.block(6 * i, 6 * j, 6, 6).norm() > 0))
          R.block(6 * i, 6 * j, 6, 6) = K.block(6 * i, 6 * j, 6, 6);
    if (kind == PrecondKind::jacobi) R = Dense(K.diagonal().asDiagonal());
    ASSERT_EQ(R.rows(), nd);
    const Dense Rinv = R.llt().solve(Dense::Identity(nd, nd));
    EXPECT_LT((Z - Rinv).norm(), 1e-9 * Rinv.norm()) << to_string(kind);
  }
}

TEST(Preconditioners, StatsComeFromTheFibresAndForest)
{
  const ContactSystem sys = pile_scene(200, SceneParams{});
  for (Form form : {Form::contact, Form::body}) {
    const bool ghosts = form == Form::contact;
    PrecondOptions opt;
    FibreStats stats;
    opt.kind = PrecondKind::fibre;
    make_preconditioner(form, sys, serial_exchange(), opt, &stats);
    const Fibres f = build_fibres(sys, opt.weight, nullptr, ghosts);
    EXPECT_EQ(stats.num_fibres, f.stats.num_fibres);
    EXPECT_EQ(stats.contacts_in_fibres, f.stats.contacts_in_fibres);
    EXPECT_EQ(stats.length_histogram, f.stats.length_histogram);
    opt.kind = PrecondKind::tree;
    make_preconditioner(form, sys, serial_exchange(), opt, &stats);
    const Forest t = build_forest(sys, opt.weight, nullptr, ghosts);
    EXPECT_EQ(stats.contacts_in_fibres, t.num_edges);
    EXPECT_EQ(stats.num_fibres, t.stats.num_fibres);
    opt.kind = PrecondKind::block;
    make_preconditioner(form, sys, serial_exchange(), opt, &stats);
    EXPECT_EQ(stats.num_fibres, 0);
  }
}

TEST(Preconditioners, DegenerateSystems)
{
  SceneParams p;
  expect_all(pair_scene(p), 1e-9, false);
  // Walls only: the tree is the body with its wall contacts.
  std::vector<Body> bodies(2);
  bodies[1].x = Vec3(5, 0, 0.99);
  bodies[0].x = Vec3(0, 0, 0.98);
  std::vector<Contact> cs{sphere_wall_contact(bodies, 0, Vec3::UnitZ(), 0.98),
                          sphere_wall_contact(bodies, 0, Vec3::UnitX(), 0.97),
                          sphere_wall_contact(bodies, 1, Vec3::UnitZ(), 0.99)};
  for (Contact &k : cs) k.compliance.fill(1e-6);
  const ContactSystem walls(bodies, cs, 6, SpookParams{});
  for (Form form : {Form::contact, Form::body}) {
    PrecondOptions opt;
    opt.kind = PrecondKind::tree;
    const auto P = make_preconditioner(form, walls, serial_exchange(), opt);
    const Dense Z = dense_inverse(form, walls, *P);
    const Dense R = form == Form::contact ? test::dense_A(walls) : test::dense_K(walls);
    EXPECT_LT((Z * R - Dense::Identity(R.rows(), R.cols())).norm(), 1e-8);
  }
  const ContactSystem empty({}, {}, 6, SpookParams{});
  for (PrecondKind kind : kKinds) {
    PrecondOptions opt;
    opt.kind = kind;
    Vector z;
    make_preconditioner(Form::contact, empty, serial_exchange(), opt)->apply(Vector(), z);
    EXPECT_EQ(z.size(), 0);
  }
}

// The preconditioner solves exactly when the system is itself a tree: a chain of spheres
// standing on the floor, whose A (contact form) and K (body form) are then fully inverted.
TEST(Preconditioners, TreeIsExactOnATreeSystem)
{
  std::vector<Body> bodies(6);
  for (int i = 0; i < 6; ++i) {
    bodies[i].radius = 0.5;
    bodies[i].mass = 1.0 + 0.1 * i;
    bodies[i].x = Vec3(0.3 * (i % 2), 0.1 * i, 0.5 + 0.95 * i);
  }
  std::vector<Contact> cs{sphere_wall_contact(bodies, 0, Vec3::UnitZ(), 0.5)};
  for (int i = 1; i < 6; ++i) cs.push_back(sphere_sphere_contact(bodies, i, i - 1));
  for (Contact &k : cs) k.compliance.fill(1e-9);
  const ContactSystem sys(bodies, cs, 6, SpookParams{});
  for (Form form : {Form::contact, Form::body})
    for (PrecondKind kind : {PrecondKind::fibre, PrecondKind::tree}) {
      PrecondOptions opt;
      opt.kind = kind;
      const auto P = make_preconditioner(form, sys, serial_exchange(), opt);
      const Dense Z = dense_inverse(form, sys, *P);
      const Dense R = form == Form::contact ? test::dense_A(sys) : test::dense_K(sys);
      // The contact-form fibre leaves the floor contact out (it is a wall contact).
      if (form == Form::contact && kind == PrecondKind::fibre) continue;
      EXPECT_LT((Z * R - Dense::Identity(R.rows(), R.cols())).norm(), 1e-7)
          << to_string(form) << " " << to_string(kind);
    }
}
