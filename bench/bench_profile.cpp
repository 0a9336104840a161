// Driver for instruction counts (valgrind --tool=callgrind) of one hot path on heap_scene:
//   bench_profile WHAT CONTACTS REPS
// WHAT: contact_fibre, contact_tree, body_fibre, body_tree (preconditioner build), fibres,
// forest (graph part only), product_A, product_K (one operator application), apply_<build>
// (one preconditioner application; operator and preconditioner are made outside the
// counted function). Only run_target() is meant to be counted:
//   valgrind --tool=callgrind --collect-atstart=no --toggle-collect='*run_target*'
//     build-perf/bench/bench_profile contact_tree 15000 10   (one command line)
// and the per-call figure is the total divided by REPS (bench/profile.sh does this).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "bench_scenes.hpp"
#include "fibre/algebra/operators.hpp"
#include "fibre/precond/preconditioner_family.hpp"

using namespace fibre;

namespace {

bool parse_build(const std::string &what, Form &form, PrecondKind &kind)
{
  if (what == "contact_fibre")
    form = Form::contact, kind = PrecondKind::fibre;
  else if (what == "contact_tree")
    form = Form::contact, kind = PrecondKind::tree;
  else if (what == "body_fibre")
    form = Form::body, kind = PrecondKind::fibre;
  else if (what == "body_tree")
    form = Form::body, kind = PrecondKind::tree;
  else
    return false;
  return true;
}

// What run_target() needs that is not to be counted: the operator and the preconditioner of
// the apply and product targets are made here.
struct Prepared {
  std::unique_ptr<LinearOperator> op;
  std::unique_ptr<Preconditioner> P;
  Vector x, y;
};

Prepared prepare(const std::string &what, const ContactSystem &sys)
{
  Prepared p;
  Form form;
  PrecondKind kind;
  if (what == "product_A" || what == "product_K") {
    p.op = make_operator(what == "product_A" ? Form::contact : Form::body, sys, serial_exchange());
    p.x = Vector::Ones(p.op->size());
  } else if (what.rfind("apply_", 0) == 0 && parse_build(what.substr(6), form, kind)) {
    PrecondOptions opt;
    opt.kind = kind;
    p.P = make_preconditioner(form, sys, serial_exchange(), opt);
    p.x = Vector::Ones(form == Form::contact ? sys.contact_dofs() : sys.body_dofs());
  } else if (!parse_build(what, form, kind) && what != "fibres" && what != "forest") {
    std::fprintf(stderr, "unknown target '%s'\n", what.c_str());
    std::exit(2);
  }
  return p;
}

// The counted part: `reps` calls of the target and nothing else.
__attribute__((noinline)) double run_target(const std::string &what, const ContactSystem &sys,
                                            Prepared &p, int reps)
{
  double sink = 0;
  Form form;
  PrecondKind kind;
  if (p.op) {
    for (int i = 0; i < reps; ++i) {
      p.op->apply(p.x, p.y);
      sink += p.y[0];
    }
  } else if (p.P) {
    for (int i = 0; i < reps; ++i) {
      p.P->apply(p.x, p.y);
      sink += p.y[0];
    }
  } else if (parse_build(what, form, kind)) {
    PrecondOptions opt;
    opt.kind = kind;
    for (int i = 0; i < reps; ++i)
      sink += make_preconditioner(form, sys, serial_exchange(), opt)->name().size();
  } else {
    for (int i = 0; i < reps; ++i)
      sink += what == "fibres" ? build_fibres(sys, EdgeWeight::z, nullptr, true).contacts.size()
                               : build_forest(sys, EdgeWeight::z, nullptr, true).order.size();
  }
  return sink;
}

} // namespace

int main(int argc, char **argv)
{
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s WHAT CONTACTS REPS\n", argv[0]);
    return 2;
  }
  const ContactSystem sys = bench::heap_scene(bench::heap_bodies_for(std::atoi(argv[2])));
  std::printf("%d bodies, %d contacts\n", sys.num_bodies(), sys.num_contacts());
  Prepared p = prepare(argv[1], sys);
  std::printf("sink %g\n", run_target(argv[1], sys, p, std::atoi(argv[3])));
  return 0;
}
