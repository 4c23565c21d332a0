// The CUDA back-end's entry points in a build without it (SEDIMENT_WITH_CUDA off or no nvcc):
// every scene with `device: cuda` is refused at load with the reason.
#include <mpm/core/error.h>

#include "device_solid.h"

namespace mpm::cuda {

bool built_with_cuda() { return false; }

namespace detail {

std::unique_ptr<DeviceSolid> make_device_solid(const DeviceScene&, bool) {
  throw Error("device: cuda: this build has no CUDA back-end");
}
std::string device_unavailable_reason() { return "this build has no CUDA back-end"; }
std::string device_description() { return "none"; }
std::size_t device_free_bytes() { return 0; }
std::size_t bytes_per_particle(bool) { return 0; }
std::size_t bytes_per_block(bool) { return 0; }
std::size_t bytes_per_table_entry() { return 0; }

}  // namespace detail
}  // namespace mpm::cuda
