# mpm::cuda: the solid step on a CUDA device (device_pipeline.h). The host side is always built;
# the kernels only with CUDA (SedimentCuda.cmake), else no_cuda.cpp refuses device: cuda.
list(APPEND MPM_CUDA_SOURCES src/cuda/device_pipeline.cpp)
if(SEDIMENT_CUDA_ENABLED)
  list(APPEND MPM_CUDA_SOURCES src/cuda/device_solid.cu)
else()
  list(APPEND MPM_CUDA_SOURCES src/cuda/no_cuda.cpp)
endif()
