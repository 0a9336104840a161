#include "fibre/core/exchange.hpp"

namespace fibre {

std::vector<long> global_body_index(const Exchange &ex, int num_owned, int num_bodies, long &total)
{
  const long offset = ex.exclusive_prefix_sum(num_owned);
  total = static_cast<long>(ex.sum(static_cast<double>(num_owned)));
  // Carry the ids through a per-body vector (doubles hold integers below 2^53 exactly).
  Vector ids = Vector::Zero(Eigen::Index(kBodyDofs) * num_bodies);
  for (int i = 0; i < num_owned; ++i) ids[6 * i] = static_cast<double>(offset + i);
  ex.forward(ids);
  std::vector<long> index(num_bodies);
  for (int i = 0; i < num_bodies; ++i) index[i] = static_cast<long>(ids[6 * i]);
  return index;
}

void ImageExchange::forward(Vector &body_vec) const
{
  for (std::size_t i = 0; i < owners_.size(); ++i)
    if (owners_[i] != int(i))
      body_vec.segment<6>(6 * Eigen::Index(i)) = body_vec.segment<6>(6 * Eigen::Index(owners_[i]));
}

void ImageExchange::reverse_sum(Vector &body_vec) const
{
  for (std::size_t i = 0; i < owners_.size(); ++i)
    if (owners_[i] != int(i)) {
      body_vec.segment<6>(6 * Eigen::Index(owners_[i])) += body_vec.segment<6>(6 * Eigen::Index(i));
      body_vec.segment<6>(6 * Eigen::Index(i)).setZero();
    }
}

namespace {

class FullHalo final : public Exchange::Halo {
 public:
  explicit FullHalo(const Exchange &ex) : ex_(ex) {}
  void sum_copies(Vector &body_vec) const override
  {
    ex_.reverse_sum(body_vec);
    ex_.forward(body_vec);
  }

 private:
  const Exchange &ex_;
};

} // namespace

std::unique_ptr<Exchange::Halo> Exchange::halo(const std::vector<char> &, bool) const
{
  return std::make_unique<FullHalo>(*this);
}

const Exchange &serial_exchange()
{
  static const SerialExchange ex;
  return ex;
}

} // namespace fibre
