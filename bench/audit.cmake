# Sensor simulation + model audit benchmark (included by bench/CMakeLists.txt).
if(TARGET tactforce::audit)
  add_executable(audit_bench ${CMAKE_CURRENT_LIST_DIR}/audit_bench.cc)
  target_link_libraries(audit_bench PRIVATE tactforce::audit benchmark::benchmark)
endif()
