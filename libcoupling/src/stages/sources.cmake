list(APPEND COUPLING_SOURCES
  src/stages/coupled_time_step.cpp
  src/stages/volume_fraction_stage.cpp
  src/stages/pore_pressure.cpp
  src/stages/mixture_projection.cpp
  src/stages/reclassify_sediment.cpp
  src/stages/bed_load.cpp
)
