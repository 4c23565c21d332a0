list(APPEND COUPLING_SOURCES
  src/stages/coupled_stages.cpp
  src/stages/reclassify_sediment.cpp
)
