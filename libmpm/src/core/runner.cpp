#include <mpm/core/runner_impl.h>

namespace mpm {

template class Runner<2>;
template class Runner<3>;

}  // namespace mpm
