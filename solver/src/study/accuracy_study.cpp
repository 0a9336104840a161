#include "fibre/study/accuracy_study.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "fibre/algebra/operators.hpp"
#include "fibre/core/text.hpp"
#include "fibre/io/system_io.hpp"

namespace fibre {

namespace {

// PREFIX.images: "image body" per line, an image being a ghost of the system and its body an
// owned one; none when the file is absent.
std::shared_ptr<const ImageExchange> read_images(const std::string &path, const ContactSystem &sys)
{
  std::ifstream in(path);
  if (!in) return nullptr;
  std::vector<int> owners(sys.num_bodies());
  for (int i = 0; i < sys.num_bodies(); ++i) owners[i] = i;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string w[3];
    words >> w[0] >> w[1] >> w[2];
    long image = -1, body = -1;
    if (!to_long(w[0], image) || !to_long(w[1], body) || !w[2].empty() ||
        image < sys.num_owned_bodies() || image >= sys.num_bodies() || body < 0 ||
        body >= sys.num_owned_bodies())
      throw std::runtime_error(path + ", line " + std::to_string(number) +
                               ": expected '<image> <body>', a ghost and an owned body");
    owners[image] = static_cast<int>(body);
  }
  return std::make_shared<const ImageExchange>(std::move(owners));
}

} // namespace

StepState read_step_state(const std::string &prefix)
{
  StepState st{read_system_file(prefix + ".sys"), Vector(), Vector(), nullptr};
  st.images = read_images(prefix + ".images", st.sys);
  const int rows = st.sys.rows(), nc = st.sys.num_contacts();
  st.lambda = Vector::Zero(st.sys.contact_dofs());
  st.warm = Vector::Zero(st.sys.contact_dofs());
  std::ifstream in(prefix + ".lambda");
  if (!in) return st; // a system alone: cold start, no run's answer
  std::string line;
  int number = 0, seen = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string x; words >> x;) w.push_back(x);
    long c = -1;
    const auto fail = [&](const std::string &what) {
      throw std::runtime_error(prefix + ".lambda, line " + std::to_string(number) + ": " + what);
    };
    if (w.size() != std::size_t(4 + rows) && w.size() != std::size_t(4 + 2 * rows))
      fail("expected " + std::to_string(4 + 2 * rows) + " values");
    if (!to_long(w[0], c) || c < 0 || c >= nc) fail("contact index out of range");
    for (int r = 0; r < rows; ++r) {
      double v = 0;
      if (!to_double(w[4 + r], v)) fail("'" + w[4 + r] + "' is not a number");
      st.lambda[Eigen::Index(rows) * c + r] = v;
      if (w.size() == std::size_t(4 + 2 * rows)) {
        if (!to_double(w[4 + rows + r], v)) fail("'" + w[4 + rows + r] + "' is not a number");
        st.warm[Eigen::Index(rows) * c + r] = v;
      }
    }
    ++seen;
  }
  if (seen != nc)
    throw std::runtime_error(prefix + ".lambda: " + std::to_string(seen) +
                             " contacts, the system has " + std::to_string(nc));
  return st;
}

double k_product_seconds(const ContactSystem &sys, int repeat)
{
  const BodySpaceOperator K(sys, serial_exchange());
  const Vector x = Vector::Random(sys.body_dofs());
  Vector y;
  std::vector<double> t;
  for (int i = 0; i < std::max(1, repeat); ++i) {
    const auto t0 = Clock::now();
    K.apply(x, y);
    t.push_back(seconds_since(t0));
  }
  std::nth_element(t.begin(), t.begin() + t.size() / 2, t.end());
  return t[t.size() / 2];
}

StudyRow measure_setting(const StepState &state, const StepOptions &opt, const Vector &reference,
                         double k_seconds, int repeat)
{
  StudyRow row;
  row.setting = describe(opt);
  StepResult res;
  row.seconds = INFINITY;
  for (int i = 0; i < std::max(1, repeat); ++i) {
    ContactSystem sys = state.sys; // the solve sets masks and the rhs
    const auto t0 = Clock::now();
    res = solve_step(sys, state.exchange(), opt, &state.warm, MPI_COMM_SELF);
    row.seconds = std::min(row.seconds, seconds_since(t0));
  }
  row.k_products = row.seconds / k_seconds;
  row.iterations = res.total_iterations;
  row.passes = res.active_set_passes;
  row.sweeps = res.sweeps;
  row.slow_restarts = res.slow_restarts;
  row.sweep_equivalents = res.sweep_equivalents;
  row.complementarity = res.complementarity;
  row.error_estimate = res.error_estimate;
  row.converged = res.converged;
  row.error = step_accuracy(state.sys, res.lambda, reference, state.exchange());
  return row;
}

} // namespace fibre
