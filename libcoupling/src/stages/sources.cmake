list(APPEND COUPLING_SOURCES
  src/stages/coupled_stages.cpp
)
