# Included from bench/CMakeLists.txt: the inertial-fitting benchmark
# (issue 5). Prints markdown tables: methods x noise levels.
add_executable(inertia_bench ${CMAKE_CURRENT_LIST_DIR}/inertia_bench.cc)
target_link_libraries(inertia_bench PRIVATE tactforce::inertia)
