# `cmake --install build --prefix P`: the libraries, the public headers under P/include/drench/,
# P/lib/cmake/drench/drenchConfig.cmake (targets drench::core and drench::bullet) and P/lib/pkgconfig/drench.pc
# (drench-bullet.pc for the adapter). tests/consumer/ builds a program against the result.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(drench_install_targets drench_core)
if(TARGET drench_bullet)
  list(APPEND drench_install_targets drench_bullet)
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
endif()

set(drench_config_dir ${CMAKE_INSTALL_LIBDIR}/cmake/drench)
install(EXPORT drenchTargets NAMESPACE drench:: DESTINATION ${drench_config_dir} FILE drenchTargets.cmake)

# What the config must find again for a consumer: the build's choices, recorded.
get_target_property(drench_core_type drench_core TYPE)
set(DRENCH_HAS_BULLET OFF)
if(TARGET drench_bullet)
  set(DRENCH_HAS_BULLET ON)
endif()
set(DRENCH_BULLET_DOUBLE_VALUE 0)
if(DRENCH_BULLET_PRECISION STREQUAL "double")
  set(DRENCH_BULLET_DOUBLE_VALUE 1)
endif()
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/drenchConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/drenchConfig.cmake INSTALL_DESTINATION ${drench_config_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/drenchConfigVersion.cmake
                                 COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/drenchConfig.cmake ${PROJECT_BINARY_DIR}/drenchConfigVersion.cmake
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
  configure_file(${CMAKE_CURRENT_LIST_DIR}/drench-bullet.pc.in ${PROJECT_BINARY_DIR}/drench-bullet.pc @ONLY)
  install(FILES ${PROJECT_BINARY_DIR}/drench-bullet.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
endif()
