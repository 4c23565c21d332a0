#include <coupling/coupled_runner.h>
#include <mpm/core/runner_impl.h>

namespace mpm {

template class Runner<2, coupling::CoupledState<2>>;
template class Runner<3, coupling::CoupledState<3>>;

}  // namespace mpm
