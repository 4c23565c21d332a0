#include "hypre_runtime.h"

#include <HYPRE_utilities.h>
#include <mpi.h>

#include <cstdlib>
#include <mutex>

namespace fluid::detail {

void ensure_hypre_initialized() {
  static std::once_flag once;
  std::call_once(once, [] {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) {
      MPI_Init(nullptr, nullptr);
      // We started MPI, so we finish it (after hypre) when the process exits.
      std::atexit([] {
        HYPRE_Finalize();
        int finalized = 0;
        MPI_Finalized(&finalized);
        if (!finalized) MPI_Finalize();
      });
    }
    HYPRE_Init();
  });
}

}  // namespace fluid::detail
