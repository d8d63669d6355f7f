# neraf_rt: the LibTorch-free runtime of exported models (include/neraf/neraf_rt.h, a C ABI).
# A shared library over BLAS (OpenBLAS through Debian's libblas.so.3) and FFTW; only the C
# symbols are exported. Sources: src/neraf/runtime/*.cpp; tests: tests/runtime/*_test.cpp
# (neraf_test_runtime, label fast); benchmarks: bench/bench_runtime*.cpp.
#
# Targets:
#   neraf_model_file  static: the MODEL.nrf reader/writer alone (model_file.cpp), for the export
#                     command, the benchmarks and tools (torch-free, no BLAS/FFTW)
#   neraf_rt          shared: the product, installed with its header, a CMake package
#                     (find_package(neraf) → neraf::neraf_rt) and pkg-config's neraf_rt.pc
#   neraf_rt_static   static: the same objects, for the tests (they reach the internals)
find_package(Threads REQUIRED)
find_library(NERAF_BLAS_LIBRARY NAMES blas REQUIRED)
find_path(NERAF_CBLAS_INCLUDE_DIR cblas.h PATH_SUFFIXES x86_64-linux-gnu REQUIRED)
include(GNUInstallDirs)

set(neraf_rt_include "${CMAKE_CURRENT_SOURCE_DIR}/include")
set(neraf_rt_internal "${CMAKE_CURRENT_SOURCE_DIR}/src")

add_library(neraf_model_file STATIC "${CMAKE_CURRENT_SOURCE_DIR}/src/neraf/runtime/model_file.cpp")
target_include_directories(neraf_model_file PUBLIC ${neraf_rt_include} ${neraf_rt_internal})
target_link_libraries(neraf_model_file PRIVATE nlohmann_json::nlohmann_json)
# PIC and hidden: it is also linked into the shared neraf_rt, whose only exports are C symbols.
set_target_properties(neraf_model_file PROPERTIES POSITION_INDEPENDENT_CODE ON
                      CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)

file(GLOB neraf_rt_srcs CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/src/neraf/runtime/*.cpp")
list(FILTER neraf_rt_srcs EXCLUDE REGEX "/model_file\\.cpp$")
add_library(neraf_rt_objects OBJECT ${neraf_rt_srcs})
target_include_directories(neraf_rt_objects PRIVATE ${neraf_rt_include} ${neraf_rt_internal}
                                                    "${NERAF_CBLAS_INCLUDE_DIR}")
target_compile_definitions(neraf_rt_objects PRIVATE NERAF_RT_BUILD)
target_link_libraries(neraf_rt_objects PRIVATE PkgConfig::FFTW nlohmann_json::nlohmann_json)
set_target_properties(neraf_rt_objects PROPERTIES POSITION_INDEPENDENT_CODE ON
                      CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
# The engine's exp/log/tanh loops (vector_math.h) vectorise only when GCC may if-convert their
# clamps, i.e. assume that float operations do not trap: no neraf code unmasks FP exceptions, and
# the flag changes no computed value (rounding and contraction are untouched).
set_source_files_properties("${CMAKE_CURRENT_SOURCE_DIR}/src/neraf/runtime/engine.cpp"
                            PROPERTIES COMPILE_OPTIONS "-fno-trapping-math")
set(neraf_rt_deps PkgConfig::FFTW ${NERAF_BLAS_LIBRARY} Threads::Threads ${CMAKE_DL_LIBS})

add_library(neraf_rt SHARED $<TARGET_OBJECTS:neraf_rt_objects>)
target_include_directories(neraf_rt PUBLIC $<BUILD_INTERFACE:${neraf_rt_include}>
                                           $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
target_link_libraries(neraf_rt PRIVATE neraf_model_file ${neraf_rt_deps})
set_target_properties(neraf_rt PROPERTIES VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR})
# Unresolved symbols are link errors here, not surprises in an application; only neraf_* exported.
target_link_options(neraf_rt PRIVATE "LINKER:--no-undefined"
                    "LINKER:--version-script=${CMAKE_CURRENT_SOURCE_DIR}/cmake/neraf_rt.map")
set_property(TARGET neraf_rt APPEND PROPERTY LINK_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/cmake/neraf_rt.map")

add_library(neraf_rt_static STATIC $<TARGET_OBJECTS:neraf_rt_objects>)
target_include_directories(neraf_rt_static PUBLIC ${neraf_rt_include} ${neraf_rt_internal})
target_link_libraries(neraf_rt_static PUBLIC neraf_model_file ${neraf_rt_deps})

# ---- installation: lib, header, CMake package, pkg-config ------------------------------------
include(CMakePackageConfigHelpers)
set(neraf_cmake_dir "${CMAKE_INSTALL_LIBDIR}/cmake/neraf")
install(TARGETS neraf_rt EXPORT neraf-targets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(FILES "${neraf_rt_include}/neraf/neraf_rt.h" DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}/neraf")
install(EXPORT neraf-targets NAMESPACE neraf:: DESTINATION "${neraf_cmake_dir}")
configure_package_config_file("${CMAKE_CURRENT_SOURCE_DIR}/cmake/neraf-config.cmake.in"
                              "${CMAKE_CURRENT_BINARY_DIR}/neraf-config.cmake"
                              INSTALL_DESTINATION "${neraf_cmake_dir}")
# 0.x: a new minor version may change the ABI (SameMinorVersion: 0.1.x accepts only 0.1.y).
write_basic_package_version_file("${CMAKE_CURRENT_BINARY_DIR}/neraf-config-version.cmake"
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES "${CMAKE_CURRENT_BINARY_DIR}/neraf-config.cmake"
              "${CMAKE_CURRENT_BINARY_DIR}/neraf-config-version.cmake"
        DESTINATION "${neraf_cmake_dir}")
# The .pc finds the prefix from its own place (relocatable, as `cmake --install --prefix` needs).
file(RELATIVE_PATH neraf_pc_to_prefix "/p/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/p")
configure_file("${CMAKE_CURRENT_SOURCE_DIR}/cmake/neraf_rt.pc.in"
               "${CMAKE_CURRENT_BINARY_DIR}/neraf_rt.pc" @ONLY)
install(FILES "${CMAKE_CURRENT_BINARY_DIR}/neraf_rt.pc"
        DESTINATION "${CMAKE_INSTALL_LIBDIR}/pkgconfig")

if(NERAF_TESTS)
  file(GLOB neraf_rt_tests CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/tests/runtime/*_test.cpp")
  if(neraf_rt_tests)
    add_executable(neraf_test_runtime ${neraf_rt_tests})
    # The internals (src/neraf/runtime/*.h) are tested directly and through the C API, against
    # neraf_dsp; the shared library itself is exercised by runtime_install below.
    target_link_libraries(neraf_test_runtime PRIVATE neraf_rt_static neraf_dsp GTest::gtest_main
                                                     Threads::Threads)
    gtest_discover_tests(neraf_test_runtime PROPERTIES LABELS fast DISCOVERY_TIMEOUT 60)
  endif()
  # A tiny random model for the install test (and for trying the example by hand).
  add_executable(neraf_rt_make_test_model
                 "${CMAKE_CURRENT_SOURCE_DIR}/tests/runtime/tools/make_test_model.cpp")
  target_link_libraries(neraf_rt_make_test_model PRIVATE neraf_model_file)
  # Installs into a temporary prefix, builds examples/auralize_path against it with
  # find_package(neraf) and runs it.
  add_test(NAME runtime_install
           COMMAND "${CMAKE_CURRENT_SOURCE_DIR}/tests/runtime/install_test.sh" "${CMAKE_BINARY_DIR}"
                   "${CMAKE_CURRENT_SOURCE_DIR}" $<TARGET_FILE:neraf_rt_make_test_model>)
  set_tests_properties(runtime_install PROPERTIES LABELS slow)
endif()
if(NERAF_BENCH)
  file(GLOB neraf_rt_bench CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/bench/bench_runtime*.cpp")
  if(neraf_rt_bench)
    add_executable(neraf_bench_runtime ${neraf_rt_bench})
    # The C API of the shared library, plus the model writer for the synthetic models.
    target_link_libraries(neraf_bench_runtime PRIVATE neraf_rt neraf_model_file benchmark::benchmark)
  endif()
endif()
