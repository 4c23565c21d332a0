list(APPEND COUPLING_SOURCES
  src/drag/drag_law.cpp
)
