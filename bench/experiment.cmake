# MuJoCo grasp-trial benchmark (included by bench/CMakeLists.txt).
if(TARGET tactforce::experiment)
  add_executable(experiment_bench ${CMAKE_CURRENT_LIST_DIR}/experiment_bench.cc)
  target_link_libraries(experiment_bench PRIVATE tactforce::experiment benchmark::benchmark)
endif()
