# Included from bench/CMakeLists.txt: the inertial-fitting benchmark
# (issue 5). Prints markdown tables: methods x noise levels.
add_executable(inertia_bench ${CMAKE_CURRENT_LIST_DIR}/inertia_bench.cc)
target_link_libraries(inertia_bench PRIVATE tactforce::inertia tactforce::experiment)
# Issue 12: DENSITY on the shared tools' meshes against the mesh-free methods.
add_executable(inertia_mesh_bench ${CMAKE_CURRENT_LIST_DIR}/inertia_mesh_bench.cc)
target_link_libraries(inertia_mesh_bench PRIVATE tactforce::inertia)
