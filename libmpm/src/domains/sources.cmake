list(APPEND MPM_CORE_SOURCES
  src/domains/particle_domains.cpp
  src/domains/surface_contact.cpp
)
