list(APPEND COUPLING_SOURCES
  src/core/volume_fraction.cpp
  src/core/momentum_exchange.cpp
  src/core/coupled_scene.cpp
  src/core/settling_column.cpp
  src/core/scene_loader.cpp
  src/core/coupled_runner.cpp
  src/core/bed_profile.cpp
  src/core/scour_prediction.cpp
  src/core/pressure_probe.cpp
  src/core/bed_load.cpp
)
