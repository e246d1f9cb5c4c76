# Torch for the model libraries. Debian's libtorch-dev puts TorchConfig here;
# for LibTorch 2.x pass -DCMAKE_PREFIX_PATH=$(python3 -c 'import torch;print(torch.utils.cmake_prefix_path)').
list(APPEND CMAKE_PREFIX_PATH /usr/lib/x86_64-linux-gnu/cmake/Torch)

# nec_torch_library(NAME SOURCES...): a library that links torch and compiles
# with a shared precompiled header (one <torch/torch.h> parse per target).
function(nec_torch_library name)
  if(NOT TARGET torch)
    find_package(Torch REQUIRED)
  endif()
  add_library(${name} ${ARGN})
  target_link_libraries(${name} PUBLIC ${TORCH_LIBRARIES})
  target_precompile_headers(${name} PRIVATE <torch/torch.h>)
endfunction()
