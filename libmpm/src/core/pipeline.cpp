#include <mpm/core/pipeline.h>

#include <algorithm>
#include <cstdio>
#include <numeric>

namespace mpm {

std::string StageTimes::table() const {
  const double total = std::accumulate(seconds.begin(), seconds.end(), 0.0);
  std::size_t width = 5;
  for (const auto& n : names) width = std::max(width, n.size());
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line, "%-*s %12s %7s\n", static_cast<int>(width), "stage", "seconds", "share");
  out += line;
  for (std::size_t s = 0; s < names.size(); ++s) {
    std::snprintf(line, sizeof line, "%-*s %12.3f %6.1f%%\n", static_cast<int>(width), names[s].c_str(), seconds[s],
                  total > 0 ? 100.0 * seconds[s] / total : 0.0);
    out += line;
  }
  std::snprintf(line, sizeof line, "%-*s %12.3f\n", static_cast<int>(width), "total", total);
  return out + line;
}

}  // namespace mpm
