list(APPEND COUPLING_SOURCES
  src/core/volume_fraction.cpp
  src/core/momentum_exchange.cpp
  src/core/coupled_scene.cpp
  src/core/settling_column.cpp
)
