# Layers only look down (docs/architecture.md): common <- {sph, ccd, io} <- coupling <- {surface, wetting}
# <- scene, and only bullet_adapter/ (with its tests and the embedding demo, which are its users) includes
# Bullet. Run by ctest as `cmake -DSOURCE_DIR=<repo> -P check_layers.cmake`; fails naming each file and
# include that breaks a rule.

cmake_minimum_required(VERSION 3.22)

set(allowed_common common)
set(allowed_sph common sph)
set(allowed_ccd common ccd)
set(allowed_io common io)
set(allowed_coupling common sph ccd coupling)
set(allowed_surface common sph ccd coupling io surface)
set(allowed_wetting common sph ccd coupling wetting)
set(allowed_scene common sph ccd io coupling surface wetting scene)
set(layers common sph ccd io coupling surface wetting scene)

set(bullet_header_regex "#include[ \t]*[<\"](btBullet|BulletSoftBody/|BulletDynamics/|BulletCollision/|LinearMath/|Bullet3)")
set(violations "")

file(GLOB_RECURSE core_files RELATIVE "${SOURCE_DIR}" "${SOURCE_DIR}/src/*.hpp" "${SOURCE_DIR}/src/*.cpp")
foreach(file IN LISTS core_files)
  string(REGEX MATCH "^src/([a-z_]+)/" _ "${file}")
  set(layer "${CMAKE_MATCH_1}")
  if(NOT layer IN_LIST layers)
    list(APPEND violations "${file}: folder src/${layer}/ has no place in the layer order of tests/check_layers.cmake")
    continue()
  endif()
  file(STRINGS "${SOURCE_DIR}/${file}" includes REGEX "^[ \t]*#[ \t]*include")
  foreach(line IN LISTS includes)
    if(line MATCHES "${bullet_header_regex}")
      list(APPEND violations "${file}: includes Bullet (${line}), which only bullet_adapter/ may")
    endif()
    if(line MATCHES "#[ \t]*include[ \t]*\"([a-z_]+)/")
      set(target "${CMAKE_MATCH_1}")
      if(target IN_LIST layers AND NOT target IN_LIST allowed_${layer})
        string(REPLACE ";" ", " allowed "${allowed_${layer}}")
        list(APPEND violations "${file}: layer ${layer} includes ${target}/ (${line}), but ${layer} may include only ${allowed}")
      endif()
    endif()
  endforeach()
endforeach()

# Outside src/: only the adapter, its tests and the embedding demo include Bullet.
file(GLOB_RECURSE other_files RELATIVE "${SOURCE_DIR}" "${SOURCE_DIR}/demos/*.cpp" "${SOURCE_DIR}/demos/*.hpp"
     "${SOURCE_DIR}/tests/*.cpp" "${SOURCE_DIR}/tests/*.hpp" "${SOURCE_DIR}/bench/*.cpp" "${SOURCE_DIR}/bench/*.hpp"
     "${SOURCE_DIR}/fuzz/*.cpp" "${SOURCE_DIR}/fuzz/*.hpp")
foreach(file IN LISTS other_files)
  if(file MATCHES "^tests/bullet_adapter/" OR file STREQUAL "demos/embed_in_bullet.cpp")
    continue()
  endif()
  file(STRINGS "${SOURCE_DIR}/${file}" includes REGEX "${bullet_header_regex}")
  foreach(line IN LISTS includes)
    list(APPEND violations "${file}: includes Bullet (${line}), which only bullet_adapter/ and its users may")
  endforeach()
endforeach()

list(LENGTH core_files checked)
if(checked EQUAL 0)
  message(FATAL_ERROR "check_layers: no files under ${SOURCE_DIR}/src")
endif()
if(violations)
  list(JOIN violations "\n  " text)
  message(FATAL_ERROR "Layering broken:\n  ${text}")
endif()
message(STATUS "check_layers: ${checked} files under src/ include only lower layers; no Bullet outside the adapter")
