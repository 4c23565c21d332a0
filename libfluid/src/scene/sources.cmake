list(APPEND FLUID_SOURCES
  src/scene/fluid_scene.cpp
)
