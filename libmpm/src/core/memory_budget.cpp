#include <mpm/core/memory_budget.h>

#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include <unistd.h>

namespace mpm {
namespace {

double g_cap = std::numeric_limits<double>::infinity();

//! MemAvailable of /proc/meminfo in bytes, or infinity where it cannot be read.
double available_memory() {
  std::ifstream meminfo("/proc/meminfo");
  for (std::string line; std::getline(meminfo, line);) {
    std::istringstream fields(line);
    std::string name;
    double kilobytes = 0.0;
    if (fields >> name >> kilobytes && name == "MemAvailable:") return kilobytes * 1024.0;
  }
  return std::numeric_limits<double>::infinity();
}

//! The resident set of this process in bytes (0 where /proc/self/statm cannot be read).
double resident_memory() {
  std::ifstream statm("/proc/self/statm");
  double pages = 0.0, resident = 0.0;
  if (!(statm >> pages >> resident)) return 0.0;
  return resident * static_cast<double>(::sysconf(_SC_PAGESIZE));
}

std::string gigabytes(double bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g GB", bytes / 1e9);
  return text;
}

}  // namespace

void cap_memory(double bytes) { g_cap = std::min(g_cap, bytes); }

double memory_headroom() {
  const double held = resident_memory();
  return std::min(held + available_memory(), g_cap) - held;
}

std::string memory_shortfall(double bytes) {
  const double held = resident_memory(), available = held + available_memory();
  const double limit = std::min(available, g_cap);
  if (held + bytes <= limit) return "";
  return "about " + gigabytes(bytes) + " more than the " + gigabytes(held) + " held, beyond the " + gigabytes(limit) +
         (g_cap < available ? " of --max-memory" : " available (MemAvailable)");
}

}  // namespace mpm
