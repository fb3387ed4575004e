# `cmake --install build --prefix P`: the libraries, the public headers under P/include/drench/,
# P/lib/cmake/drench/drenchConfig.cmake (targets drench::core, drench::bullet and the adapter in each Bullet
# precision built, drench::bullet_double and drench::bullet_single) and P/lib/pkgconfig/drench.pc
# (drench-bullet.pc, drench-bullet-double.pc and drench-bullet-single.pc for the adapters).
# tests/consumer/ builds programs against the result.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(drench_install_targets drench_core)
if(TARGET drench_bullet)
  list(APPEND drench_install_targets drench_bullet)
  foreach(precision IN LISTS DRENCH_BULLET_PRECISIONS)
    list(APPEND drench_install_targets drench_bullet_${precision})
  endforeach()
endif()
install(TARGETS ${drench_install_targets} EXPORT drenchTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

# The stages' shared state and the loader's section readers are the library's own business.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/src/drench DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.hpp"
        PATTERN "coupler_stages.hpp" EXCLUDE
        PATTERN "load_sections.hpp" EXCLUDE
        PATTERN "json_reader.hpp" EXCLUDE)
if(TARGET drench_bullet)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/bullet_adapter/drench DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
          FILES_MATCHING PATTERN "*.hpp")
  # The link guards go where drenchConfig.cmake and the .pc files find them, whatever DRENCH_BULLET_LINK_GUARD
  # was here: the user of the package decides.
  foreach(precision IN LISTS DRENCH_BULLET_PRECISIONS)
    install(FILES ${PROJECT_SOURCE_DIR}/bullet_adapter/bullet_link_guard/drench_bullet_${precision}.ld
            DESTINATION ${CMAKE_INSTALL_LIBDIR}/drench)
  endforeach()
endif()

set(drench_config_dir ${CMAKE_INSTALL_LIBDIR}/cmake/drench)
install(EXPORT drenchTargets NAMESPACE drench:: DESTINATION ${drench_config_dir} FILE drenchTargets.cmake)

# What the config must find again for a consumer: the build's choices, recorded.
get_target_property(drench_core_type drench_core TYPE)
set(DRENCH_HAS_BULLET OFF)
if(TARGET drench_bullet)
  set(DRENCH_HAS_BULLET ON)
endif()
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/drenchConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/drenchConfig.cmake INSTALL_DESTINATION ${drench_config_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/drenchConfigVersion.cmake
                                 COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/drenchConfig.cmake ${PROJECT_BINARY_DIR}/drenchConfigVersion.cmake
              ${CMAKE_CURRENT_LIST_DIR}/bullet_precision_check.cmake
        DESTINATION ${drench_config_dir})

# pkg-config, for builds without CMake. A static drench needs its private dependencies at link time too.
if(drench_core_type STREQUAL "STATIC_LIBRARY")
  # fcl.pc's Cflags carry -std=c++11, which would override a user's C++17: its libraries go in by name.
  set(drench_pc_requires_private "gmpxx libcrypto ccd octomap")
  set(drench_pc_libs_private "-lfcl -lopenvdb -ltbb -ltinyobjloader_double")
else()
  set(drench_pc_requires_private "")
  set(drench_pc_libs_private "")
endif()
# Relocatable: the prefix is found from the .pc file's own place, so `cmake --install --prefix P` works.
file(RELATIVE_PATH drench_pc_up "/root/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/root")
set(drench_pc_prefix "\${pcfiledir}/${drench_pc_up}")
configure_file(${CMAKE_CURRENT_LIST_DIR}/drench.pc.in ${PROJECT_BINARY_DIR}/drench.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/drench.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
if(TARGET drench_bullet)
  # drench-bullet.pc is the adapter of DRENCH_BULLET_PRECISION, as drench::bullet.
  foreach(precision IN LISTS DRENCH_BULLET_PRECISIONS)
    set(drench_pc_precision ${precision})
    set(drench_pc_bullet_module ${DRENCH_BULLET_MODULE_${precision}})
    set(drench_pc_double 0)
    if(precision STREQUAL "double")
      set(drench_pc_double 1)
    endif()
    set(drench_pc_link_guard "")
    if(CMAKE_SYSTEM_NAME STREQUAL "Linux")
      set(drench_pc_link_guard "\${libdir}/drench/drench_bullet_${precision}.ld")
    endif()
    configure_file(${CMAKE_CURRENT_LIST_DIR}/drench-bullet-precision.pc.in
                   ${PROJECT_BINARY_DIR}/drench-bullet-${precision}.pc @ONLY)
    install(FILES ${PROJECT_BINARY_DIR}/drench-bullet-${precision}.pc
            DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
  endforeach()
  configure_file(${CMAKE_CURRENT_LIST_DIR}/drench-bullet.pc.in ${PROJECT_BINARY_DIR}/drench-bullet.pc @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/drench-bullet.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
endif()
