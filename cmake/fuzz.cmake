# libFuzzer targets for the parsers of untrusted input that build without LibTorch (fuzz/,
# fuzz/README.md; run them with scripts/fuzz.sh). Included from CMakeLists.txt when NERAF_FUZZ is
# ON, after the torch-free stages and the runtime are declared and before the LibTorch stages.
#
#   cmake -S . -B build-fuzz -G Ninja -DNERAF_FUZZ=ON -DNERAF_WITH_TORCH=OFF -DNERAF_TESTS=OFF \
#         -DNERAF_BENCH=OFF -DNERAF_NATIVE=OFF -DCMAKE_BUILD_TYPE=Debug \
#         -DCMAKE_C_COMPILER=clang-14 -DCMAKE_CXX_COMPILER=clang++-14
#   cmake --build build-fuzz --target neraf_fuzz
#
# Targets: fuzz_<name> for every fuzz/fuzz_<name>.cpp, and neraf_fuzz (all of them).
if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  message(FATAL_ERROR "NERAF_FUZZ needs clang (libFuzzer), not ${CMAKE_CXX_COMPILER_ID}; "
                      "configure with -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++")
endif()
# Every library below is compiled with sanitizer instrumentation, so whatever else links them
# (the tests, benchmarks, the LibTorch stages and the program) would need the sanitizer runtimes
# too: a fuzz build folder holds the fuzzers only.
if(NERAF_WITH_TORCH OR NERAF_TESTS OR NERAF_BENCH)
  message(FATAL_ERROR "NERAF_FUZZ needs -DNERAF_WITH_TORCH=OFF -DNERAF_TESTS=OFF -DNERAF_BENCH=OFF "
                      "(a separate build folder, e.g. build-fuzz; see scripts/fuzz.sh)")
endif()

# The libraries are instrumented for coverage and checked by ASan/UBSan; only the fuzz executables
# link libFuzzer's main. UBSan findings abort (no recovery), so libFuzzer sees them as crashes, and
# assert() stays on whatever the build type (-UNDEBUG after Release's -DNDEBUG): a failed assertion
# is a finding too.
set(NERAF_FUZZ_COMMON_FLAGS -fno-sanitize-recover=undefined -fno-omit-frame-pointer -g -O1 -UNDEBUG)
set(NERAF_FUZZ_LIB_FLAGS -fsanitize=fuzzer-no-link,address,undefined ${NERAF_FUZZ_COMMON_FLAGS})
set(NERAF_FUZZ_EXE_FLAGS -fsanitize=fuzzer,address,undefined ${NERAF_FUZZ_COMMON_FLAGS})

# The simulator's scene JSON is torch-free, but CMakeLists.txt declares neraf_sim only in a LibTorch
# build: compile its sources here, into a library for the fuzzers alone.
file(GLOB neraf_fuzz_sim_srcs CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/src/neraf/sim/*.cpp")
add_library(neraf_fuzz_sim STATIC ${neraf_fuzz_sim_srcs})
target_link_libraries(neraf_fuzz_sim PUBLIC neraf_io neraf_dsp neraf_geometry)

# The data stage is a LibTorch library too, but its parsers of pose, split and transforms.json
# files live in torch-free files of their own (data/pose_files.h, data/transforms_json.h): compiled
# here for the fuzzers alone, as the simulator is.
set(neraf_fuzz_src "${CMAKE_CURRENT_SOURCE_DIR}/src/neraf")
add_library(neraf_fuzz_data STATIC "${neraf_fuzz_src}/data/problem.cpp"
                                   "${neraf_fuzz_src}/data/pose_files.cpp"
                                   "${neraf_fuzz_src}/data/transforms_json.cpp")
target_link_libraries(neraf_fuzz_data PUBLIC neraf_io neraf_geometry)
# Likewise the run manifests: RUN/config.json (train_config_json.cpp, with the radiance field's
# config tables of nerf/config.cpp) and what is read back from RUN/data.json (run_manifest.cpp).
add_library(neraf_fuzz_infer STATIC "${neraf_fuzz_src}/infer/run_manifest.cpp"
                                    "${neraf_fuzz_src}/infer/train_config_json.cpp"
                                    "${neraf_fuzz_src}/nerf/config.cpp")
target_link_libraries(neraf_fuzz_infer PUBLIC neraf_fuzz_data)

foreach(lib neraf_util neraf_io neraf_dsp neraf_metrics neraf_geometry neraf_model_file
            neraf_rt_objects neraf_fuzz_sim neraf_fuzz_data neraf_fuzz_infer)
  target_compile_options(${lib} PRIVATE ${NERAF_FUZZ_LIB_FLAGS})
endforeach()
# The shared neraf_rt links its (now instrumented) objects with --no-undefined and no sanitizer
# runtime, so it cannot link here; the fuzzers use neraf_rt_static, so leave it out of `all`.
set_target_properties(neraf_rt PROPERTIES EXCLUDE_FROM_ALL ON)

# What each target links: the stage its parser lives in (and only that).
set(neraf_fuzz_libs_audio_file neraf_io)
set(neraf_fuzz_libs_npy neraf_io)
set(neraf_fuzz_libs_sealed_file neraf_io)
set(neraf_fuzz_libs_json_file neraf_io)
set(neraf_fuzz_libs_trajectory neraf_geometry)
set(neraf_fuzz_libs_trajectory_file neraf_geometry)
set(neraf_fuzz_libs_model_file neraf_model_file)
set(neraf_fuzz_libs_model_payload neraf_model_file)
set(neraf_fuzz_libs_c_api neraf_rt_static)
set(neraf_fuzz_libs_scene_json neraf_fuzz_sim)
set(neraf_fuzz_libs_transforms_json neraf_fuzz_data)
set(neraf_fuzz_libs_points_txt neraf_fuzz_data)
set(neraf_fuzz_libs_soundspaces_split neraf_fuzz_data)
set(neraf_fuzz_libs_raf_split neraf_fuzz_data)
set(neraf_fuzz_libs_raf_poses neraf_fuzz_data)
set(neraf_fuzz_libs_run_config neraf_fuzz_infer)
set(neraf_fuzz_libs_data_manifest neraf_fuzz_infer)

add_custom_target(neraf_fuzz)
file(GLOB neraf_fuzz_srcs CONFIGURE_DEPENDS "${CMAKE_CURRENT_SOURCE_DIR}/fuzz/fuzz_*.cpp")
foreach(src ${neraf_fuzz_srcs})
  get_filename_component(exe ${src} NAME_WE)  # fuzz_<name>
  string(REGEX REPLACE "^fuzz_" "" name ${exe})
  if(NOT DEFINED neraf_fuzz_libs_${name})
    message(FATAL_ERROR "fuzz/${exe}.cpp: add set(neraf_fuzz_libs_${name} ...) to cmake/fuzz.cmake")
  endif()
  add_executable(${exe} ${src})
  target_include_directories(${exe} PRIVATE "${CMAKE_CURRENT_SOURCE_DIR}/fuzz")
  target_compile_options(${exe} PRIVATE ${NERAF_FUZZ_EXE_FLAGS})
  target_link_options(${exe} PRIVATE ${NERAF_FUZZ_EXE_FLAGS})
  target_link_libraries(${exe} PRIVATE ${neraf_fuzz_libs_${name}} nlohmann_json::nlohmann_json)
  set_target_properties(${exe} PROPERTIES RUNTIME_OUTPUT_DIRECTORY "${CMAKE_BINARY_DIR}/fuzz")
  add_dependencies(neraf_fuzz ${exe})
endforeach()
