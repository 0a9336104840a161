#include "fibre/core/text.hpp"

#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace fibre {

bool to_double(const char *text, double &value)
{
  if (!text || !*text) return false;
  char *end = nullptr;
  errno = 0;
  value = std::strtod(text, &end);
  // ERANGE also flags an underflow to a subnormal or zero, which is a value like any other
  const bool range_ok = errno == 0 || (errno == ERANGE && std::fabs(value) < DBL_MIN);
  return end != text && *end == '\0' && range_ok && std::isfinite(value);
}

bool to_long(const char *text, long &value)
{
  if (!text || !*text) return false;
  char *end = nullptr;
  errno = 0;
  value = std::strtol(text, &end, 10);
  return end != text && *end == '\0' && errno == 0;
}

std::string format_g(double x)
{
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", x);
  return buf;
}

} // namespace fibre
