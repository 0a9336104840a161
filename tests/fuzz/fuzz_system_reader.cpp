// libFuzzer target: the system-file reader must never crash, whatever the input. It may
// reject the input with std::runtime_error. What it accepts must write and read back to the
// same system (a cheap oracle that catches silent misreads).
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "fibre/io/system_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size)
{
  const std::string_view text(reinterpret_cast<const char *>(data), size);
  fibre::ContactSystem sys;
  try {
    sys = fibre::parse_system(text);
  } catch (const std::runtime_error &) {
    return 0; // rejected with a message: fine
  }
  std::ostringstream once, twice;
  fibre::write_system(once, sys);
  const fibre::ContactSystem back = fibre::parse_system(once.str());
  fibre::write_system(twice, back);
  if (once.str() != twice.str()) __builtin_trap();
  return 0;
}
