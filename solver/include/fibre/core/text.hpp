// Small helpers every front end and tool shares: strict number parsing and wall-clock timing.
#pragma once

#include <chrono>
#include <string>

namespace fibre {

// The whole text is one finite number (to_double) or one base-10 integer (to_long); nothing
// else is accepted: no trailing characters, no empty text, no overflow.
bool to_double(const char *text, double &value);
bool to_long(const char *text, long &value);
inline bool to_double(const std::string &text, double &value)
{
  return to_double(text.c_str(), value);
}
inline bool to_long(const std::string &text, long &value)
{
  return to_long(text.c_str(), value);
}

// "%.6g" of x.
std::string format_g(double x);

using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t0)
{
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

} // namespace fibre
