# neraf_rt: the LibTorch-free runtime of exported models (include/neraf/neraf_rt.h, a C ABI).
# A shared library over BLAS (OpenBLAS through Debian's libblas.so.3) and FFTW; only the C
# symbols are exported. Sources: src/neraf/runtime/*.cpp; tests: tests/runtime/*_test.cpp
# (neraf_test_runtime, label fast); benchmarks: bench/bench_runtime*.cpp.
find_package(Threads REQUIRED)
find_library(NERAF_BLAS_LIBRARY NAMES blas REQUIRED)
find_path(NERAF_CBLAS_INCLUDE_DIR cblas.h PATH_SUFFIXES x86_64-linux-gnu REQUIRED)

file(GLOB neraf_rt_srcs CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/src/neraf/runtime/*.cpp")
add_library(neraf_rt SHARED ${neraf_rt_srcs})
target_include_directories(neraf_rt
  PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>
  PRIVATE "${CMAKE_CURRENT_SOURCE_DIR}/src" "${NERAF_CBLAS_INCLUDE_DIR}")
target_compile_definitions(neraf_rt PRIVATE NERAF_RT_BUILD NERAF_VERSION="${PROJECT_VERSION}")
set_target_properties(neraf_rt PROPERTIES CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON
                                          VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR})
target_link_libraries(neraf_rt PRIVATE PkgConfig::FFTW ${NERAF_BLAS_LIBRARY} Threads::Threads)

if(NERAF_TESTS)
  file(GLOB neraf_rt_tests CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/tests/runtime/*_test.cpp")
  if(neraf_rt_tests)
    add_executable(neraf_test_runtime ${neraf_rt_tests})
    # The internals (src/neraf/runtime/*.h) are tested through the C API and against neraf_dsp.
    target_include_directories(neraf_test_runtime PRIVATE "${CMAKE_CURRENT_SOURCE_DIR}/src")
    target_link_libraries(neraf_test_runtime PRIVATE neraf_rt neraf_dsp GTest::gtest_main Threads::Threads)
    gtest_discover_tests(neraf_test_runtime PROPERTIES LABELS fast DISCOVERY_TIMEOUT 60)
  endif()
endif()
if(NERAF_BENCH)
  file(GLOB neraf_rt_bench CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/bench/bench_runtime*.cpp")
  if(neraf_rt_bench)
    add_executable(neraf_bench_runtime ${neraf_rt_bench})
    target_link_libraries(neraf_bench_runtime PRIVATE neraf_rt benchmark::benchmark)
  endif()
endif()
