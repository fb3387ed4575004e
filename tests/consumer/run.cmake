# Builds and runs tests/consumer/ against drench one way, as a user's project would:
#   cmake -DMODE=package|pkgconfig|fetchcontent|subdirectory -DDRENCH_SOURCE_DIR=<checkout> -DDRENCH_BUILD_DIR=<build>
#         -DWORK_DIR=<scratch> [-DCONSUMER_ARGS=<-D...;-D...>] [-DEXPECT_CONFIGURE_ERROR=<regex>]
#         [-DPKG_MODULES=<module;module>] [-DEXPECT_BUILD_ERROR=<regex>] [-DCONFIGURE_ONLY=ON] -P run.cmake
# package and pkgconfig install DRENCH_BUILD_DIR into WORK_DIR/prefix first (pkgconfig then compiles with the
# flags of `pkg-config --static` of PKG_MODULES, drench-bullet by default, in that order, as a build without
# CMake would); fetchcontent clones the checkout's HEAD.
# With EXPECT_CONFIGURE_ERROR the consumer must fail to configure with a message matching it; with
# EXPECT_BUILD_ERROR (pkgconfig) fail to build with one. CONFIGURE_ONLY stops after a configure that must
# succeed.
cmake_minimum_required(VERSION 3.22)

foreach(var MODE DRENCH_SOURCE_DIR WORK_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run.cmake needs -D${var}=...")
  endif()
endforeach()
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
cmake_host_system_information(RESULT cores QUERY NUMBER_OF_LOGICAL_CORES)

function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "consumer (${MODE}): ${what} failed (${code})\n${out}\n${err}")
  endif()
  message(STATUS "consumer (${MODE}): ${what} done")
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

set(args -DDRENCH_CONSUME=${MODE} -DDRENCH_SOURCE_DIR=${DRENCH_SOURCE_DIR} -DCMAKE_BUILD_TYPE=Release
         ${CONSUMER_ARGS})
if(MODE STREQUAL "package" OR MODE STREQUAL "pkgconfig")
  run_step("install of ${DRENCH_BUILD_DIR}" ${CMAKE_COMMAND} --install "${DRENCH_BUILD_DIR}" --prefix
           "${WORK_DIR}/prefix")
  list(APPEND args "-DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix")
endif()
if(MODE STREQUAL "pkgconfig")
  set(ENV{PKG_CONFIG_PATH} "${WORK_DIR}/prefix/lib/pkgconfig")
  if(NOT DEFINED PKG_MODULES)
    set(PKG_MODULES drench-bullet)
  endif()
  run_step("pkg-config" pkg-config --cflags --libs --static ${PKG_MODULES})
  separate_arguments(flags UNIX_COMMAND "${step_output}")
  if(DEFINED EXPECT_BUILD_ERROR)
    execute_process(COMMAND c++ -std=c++17 -O2 "${CMAKE_CURRENT_LIST_DIR}/jet_on_pinned_cloth.cpp" ${flags} -o
                            "${WORK_DIR}/jet_on_pinned_cloth"
                    RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
    if(code EQUAL 0)
      message(FATAL_ERROR "consumer (${MODE}): built, but should have failed with '${EXPECT_BUILD_ERROR}'")
    endif()
    string(REGEX REPLACE "[ \t\r\n]+" " " flat "${out} ${err}")
    if(NOT flat MATCHES "${EXPECT_BUILD_ERROR}")
      message(FATAL_ERROR "consumer (${MODE}): failed to build, but not with '${EXPECT_BUILD_ERROR}':\n${err}")
    endif()
    message(STATUS "consumer (${MODE}): refused as expected")
    return()
  endif()
  run_step("build" c++ -std=c++17 -O2 "${CMAKE_CURRENT_LIST_DIR}/jet_on_pinned_cloth.cpp" ${flags} -o
           "${WORK_DIR}/jet_on_pinned_cloth")
  run_step("run" "${WORK_DIR}/jet_on_pinned_cloth")
  message(STATUS "${step_output}")
  return()
endif()

set(configure ${CMAKE_COMMAND} -S "${CMAKE_CURRENT_LIST_DIR}" -B "${WORK_DIR}/build" ${args})
if(DEFINED EXPECT_CONFIGURE_ERROR)
  execute_process(COMMAND ${configure} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(code EQUAL 0)
    message(FATAL_ERROR "consumer (${MODE}): configured, but should have failed with '${EXPECT_CONFIGURE_ERROR}'")
  endif()
  string(REGEX REPLACE "[ \t\r\n]+" " " flat "${out} ${err}")
  if(NOT flat MATCHES "${EXPECT_CONFIGURE_ERROR}")
    message(FATAL_ERROR "consumer (${MODE}): failed to configure, but not with '${EXPECT_CONFIGURE_ERROR}':\n${err}")
  endif()
  message(STATUS "consumer (${MODE}): refused as expected")
  return()
endif()
run_step("configure" ${configure})
if(CONFIGURE_ONLY)
  return()
endif()
run_step("build" ${CMAKE_COMMAND} --build "${WORK_DIR}/build" -j${cores} --target jet_on_pinned_cloth)
run_step("run" "${WORK_DIR}/build/jet_on_pinned_cloth")
message(STATUS "${step_output}")
