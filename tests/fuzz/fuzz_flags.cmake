# Included right after project() (CMAKE_PROJECT_INCLUDE) by scripts/fuzz.sh:
#   cmake -DCMAKE_PROJECT_INCLUDE=tests/fuzz/fuzz_flags.cmake -DTACTFORCE_FUZZ=ON
# so that EVERY library of the project is compiled with libFuzzer's coverage
# instrumentation (fuzzer-no-link) and ASan + UBSan before the folders are
# added; tests/fuzz/CMakeLists.txt then links the targets with
# -fsanitize=fuzzer. Clang only. Third-party libraries are Debian's
# gcc-built ones, not instrumented (same libstdc++, so they link as they are).
option(TACTFORCE_FUZZ "Build tests/fuzz as libFuzzer targets (clang; scripts/fuzz.sh)" OFF)
if(TACTFORCE_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "TACTFORCE_FUZZ needs clang (CXX=clang++): libFuzzer is clang's")
  endif()
  # -O1 -g without NDEBUG: assertions (ours and Eigen's) stay on.
  set(CMAKE_CXX_FLAGS_RELWITHDEBINFO "-O1 -g" CACHE STRING "Fuzz build flags" FORCE)
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=all
                      -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
  set(TACTFORCE_FUZZ_FLAGS_APPLIED ON)
endif()
