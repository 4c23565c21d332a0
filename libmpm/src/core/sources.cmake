list(APPEND MPM_CORE_SOURCES
  src/core/config.cpp
  src/core/command_line.cpp
  src/core/sparse_grid.cpp
  src/core/particle_buckets.cpp
  src/core/transfer.cpp
  src/core/app.cpp
  src/core/pipeline.cpp
  src/core/scene_settings.cpp
  src/core/runner.cpp
  src/core/stages/sort_particles.cpp
  src/core/stages/particles_to_grid.cpp
  src/core/stages/grid_velocity_update.cpp
  src/core/stages/grid_boundary.cpp
  src/core/stages/grid_to_particles.cpp
  src/core/stages/time_step_control.cpp
)
