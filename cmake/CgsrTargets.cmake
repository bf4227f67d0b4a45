# Helpers shared by every module: warnings, sanitizers and the precompiled torch header.

function(cgsr_target_defaults target)
  target_include_directories(${target} PUBLIC ${CGSR_SOURCE_ROOT})
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-unused-parameter)
  if(CGSR_SANITIZE)
    # Any undefined behaviour aborts (fails the test) instead of printing and going on.
    target_compile_options(${target} PUBLIC -fsanitize=address,undefined -fno-sanitize-recover=undefined
                                            -fno-omit-frame-pointer -g1)
    target_link_options(${target} PUBLIC -fsanitize=address,undefined)
  endif()
  if(CGSR_FUZZ)
    # Coverage for libFuzzer in every library; the fuzz targets add -fsanitize=fuzzer (main).
    target_compile_options(${target} PUBLIC -fsanitize=fuzzer-no-link,address,undefined
                                            -fno-sanitize-recover=all -fno-omit-frame-pointer -g1)
    target_link_options(${target} PUBLIC -fsanitize=address,undefined)
  endif()
endfunction()

# Compiling <torch/torch.h> costs ~20 s per translation unit on this machine. The header is
# precompiled once, in cgsr_core, and every other target reuses that PCH (same flags).
function(cgsr_use_torch_pch target)
  if(TARGET cgsr_core AND NOT target STREQUAL "cgsr_core")
    target_precompile_headers(${target} REUSE_FROM cgsr_core)
  else()
    target_precompile_headers(${target} PRIVATE ${CGSR_SOURCE_ROOT}/core/torch_pch.h)
  endif()
endfunction()

# cgsr_add_module(NAME SOURCES ... DEPENDS ...): one library per module folder.
function(cgsr_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPENDS" ${ARGN})
  add_library(cgsr_${name} STATIC ${ARG_SOURCES})
  cgsr_target_defaults(cgsr_${name})
  target_link_libraries(cgsr_${name} PUBLIC ${ARG_DEPENDS})
  cgsr_use_torch_pch(cgsr_${name})
endfunction()
