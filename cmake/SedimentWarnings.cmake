# sediment_set_warnings(target): the project's warning set; errors when
# SEDIMENT_WARNINGS_AS_ERRORS is ON (CI), sanitizers when SEDIMENT_SANITIZE is ON.
function(sediment_set_warnings target)
  # C++ sources; CUDA sources (nvcc) get nvcc's own warnings.
  target_compile_options(${target} PRIVATE $<$<COMPILE_LANGUAGE:CXX>:-Wall -Wextra -Wpedantic -Wshadow
    -Wnon-virtual-dtor -Wno-deprecated-declarations
    # GCC 12 reports false -Wrestrict positives inside std::string at -O3 (GCC bug 105651).
    # and false -Wmaybe-uninitialized positives inside Eigen's fixed-size decompositions.
    $<$<CXX_COMPILER_ID:GNU>:-Wno-restrict -Wno-maybe-uninitialized>>)
  if(SEDIMENT_WARNINGS_AS_ERRORS)
    target_compile_options(${target} PRIVATE $<$<COMPILE_LANGUAGE:CXX>:-Werror>
      $<$<COMPILE_LANGUAGE:CUDA>:--Werror=all-warnings>)
  endif()
  if(SEDIMENT_SANITIZE)
    target_compile_options(${target} PRIVATE $<$<COMPILE_LANGUAGE:CXX>:-fsanitize=address,undefined
      -fno-omit-frame-pointer -fno-sanitize-recover=undefined>)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
endfunction()
