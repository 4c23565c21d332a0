list(APPEND MPM_CORE_SOURCES
  src/io/atomic_file.cpp
  src/io/hdf5_file.cpp
  src/io/particle_output.cpp
  src/io/cell_output.cpp
  src/io/surface_output.cpp
  src/io/checkpoint.cpp
  src/io/png_preview.cpp
  src/io/diagnostics_csv.cpp
  src/io/summary_json.cpp
)
