list(APPEND COUPLING_SOURCES
  src/core/volume_fraction.cpp
  src/core/momentum_exchange.cpp
)
