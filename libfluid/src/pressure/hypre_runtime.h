#pragma once
//! Private: MPI and hypre start-up shared by the hypre back-ends.

namespace fluid::detail {

//! Calls MPI_Init (when MPI_Initialized says no) and HYPRE_Init once per process; the
//! back-ends then work on MPI_COMM_WORLD, so the same calls run distributed later.
void ensure_hypre_initialized();

}  // namespace fluid::detail
