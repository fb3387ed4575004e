# Layers only look down (docs/architecture.md): common <- {sph, ccd, io} <- coupling <- {surface, wetting}
# <- scene; the renderer (render/, drench_render) sits above the core, which never includes it; and only
# bullet_adapter/ (with its tests, the consumer test and the embedding demos, its users) includes
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
  if(NOT file MATCHES "^src/drench/([a-z_]+)/")
    list(APPEND violations "${file}: the core's files live under src/drench/<layer>/, so that they are included as <drench/<layer>/...>")
    continue()
  endif()
  set(layer "${CMAKE_MATCH_1}")
  if(NOT layer IN_LIST layers)
    list(APPEND violations "${file}: folder src/drench/${layer}/ has no place in the layer order of tests/check_layers.cmake")
    continue()
  endif()
  file(STRINGS "${SOURCE_DIR}/${file}" includes REGEX "^[ \t]*#[ \t]*include")
  foreach(line IN LISTS includes)
    if(line MATCHES "${bullet_header_regex}")
      list(APPEND violations "${file}: includes Bullet (${line}), which only bullet_adapter/ may")
    endif()
    if(line MATCHES "#[ \t]*include[ \t]*\"([a-z_]+)/")
      list(APPEND violations "${file}: ${line}: drench's headers are included as <drench/${CMAKE_MATCH_1}/...>")
    endif()
    if(line MATCHES "#[ \t]*include[ \t]*<drench/bullet/")
      list(APPEND violations "${file}: includes the Bullet adapter (${line}), which the core may not")
    endif()
    if(line MATCHES "#[ \t]*include[ \t]*<drench/render/")
      list(APPEND violations "${file}: includes the renderer (${line}), which the core may not: it links OpenGL")
    endif()
    if(line MATCHES "#[ \t]*include[ \t]*<drench/([a-z_]+)/")
      set(target "${CMAKE_MATCH_1}")
      if(target IN_LIST layers AND NOT target IN_LIST allowed_${layer})
        string(REPLACE ";" ", " allowed "${allowed_${layer}}")
        list(APPEND violations "${file}: layer ${layer} includes ${target}/ (${line}), but ${layer} may include only ${allowed}")
      endif()
    endif()
  endforeach()
endforeach()

# Outside src/: only the adapter, its tests and the embedding demos (embed_in_bullet, bullet_playground, and
# buoyancy_tank, the tank world the buoyancy test and bench share) include Bullet.
file(GLOB_RECURSE other_files RELATIVE "${SOURCE_DIR}" "${SOURCE_DIR}/render/*.cpp" "${SOURCE_DIR}/render/*.hpp"
     "${SOURCE_DIR}/demos/*.cpp" "${SOURCE_DIR}/demos/*.hpp"
     "${SOURCE_DIR}/tests/*.cpp" "${SOURCE_DIR}/tests/*.hpp" "${SOURCE_DIR}/bench/*.cpp" "${SOURCE_DIR}/bench/*.hpp"
     "${SOURCE_DIR}/fuzz/*.cpp" "${SOURCE_DIR}/fuzz/*.hpp")
foreach(file IN LISTS other_files)
  if(file MATCHES "^tests/(bullet_adapter|consumer)/" OR file MATCHES "^demos/(embed_in_bullet|bullet_playground|buoyancy_tank)")
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
