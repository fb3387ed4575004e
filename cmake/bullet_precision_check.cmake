# A program that links a drench Bullet adapter and Bullet of the other precision configures, compiles and
# links, then crashes at start: the dynamic loader binds the names both Bullets define to whichever it loads
# first, and bullet_conversions.hpp's static_assert cannot see it (the program compiles in the adapter's
# precision, which drench::bullet gives it). This check refuses such a program at the end of the configure,
# whatever order it found Bullet and drench in: it walks the link libraries of every target of the project,
# transitively, and fails naming each target whose libraries hold a drench adapter and the other precision's
# Bullet (a library file or name: Debian's double-precision Bullet ends in -float64, as pkg-config's
# bullet-float64 and drench::bullet_double link it), another adapter of the other precision, or a precision
# the project asked for (drenchConfig.cmake records DRENCH_BULLET_PRECISION or Bullet's BULLET_DEFINITIONS).
# A generator expression it cannot read (other than a condition, whose library counts as linked) is skipped:
# the link guard (bullet_adapter/bullet_link_guard/) is behind it. Used by bullet_adapter/CMakeLists.txt and,
# installed beside it, by drenchConfig.cmake.
include_guard(GLOBAL)

# Sets `out` to double or single if `item` (a library path, file or name, or -l<name>) is a Bullet library,
# else to "".
function(_drench_bullet_library_precision item out)
  get_filename_component(name "${item}" NAME)
  string(REGEX REPLACE "^-l" "" name "${name}")
  string(REGEX REPLACE "^lib" "" name "${name}")
  string(REGEX REPLACE "\\.(so|a|dylib|lib|dll)(\\.[0-9.]+)?$" "" name "${name}")
  set(precision "")
  if(name MATCHES "^(LinearMath|Bullet[A-Za-z0-9_]*)(-float64)?$")
    if(CMAKE_MATCH_2)
      set(precision double)
    else()
      set(precision single)
    endif()
  endif()
  set(${out} "${precision}" PARENT_SCOPE)
endfunction()

# Sets `out` to the link item inside the generator expressions CMake itself writes around link libraries
# ($<LINK_ONLY:x>, $<BUILD_INTERFACE:x>, a condition $<$<...>:x>, ...), "" for $<INSTALL_INTERFACE:x>, and
# any other generator expression stripped.
function(_drench_unwrap_link_item item out)
  while(item MATCHES "^\\$<(LINK_ONLY|BUILD_INTERFACE|BUILD_LOCAL_INTERFACE|TARGET_NAME_IF_EXISTS):(.*)>$")
    set(item "${CMAKE_MATCH_2}")
  endwhile()
  if(item MATCHES "^\\$<INSTALL_INTERFACE:")
    set(item "")
  elseif(item MATCHES "^\\$<\\$<.*>:(.*)>$")
    _drench_unwrap_link_item("${CMAKE_MATCH_1}" item)
  endif()
  string(GENEX_STRIP "${item}" item)
  set(${out} "${item}" PARENT_SCOPE)
endfunction()

# Appends to the list variable named `_drench_list` the values of the named properties of `target` that are
# set (the odd name, so that it is never the caller's variable).
function(_drench_append_property _drench_list target)
  set(values ${${_drench_list}})
  foreach(property IN LISTS ARGN)
    get_target_property(value ${target} ${property})
    if(NOT value STREQUAL "value-NOTFOUND")
      list(APPEND values ${value})
    endif()
  endforeach()
  set(${_drench_list} "${values}" PARENT_SCOPE)
endfunction()

# Walks the link libraries of `target`, transitively, and sets `adapters_out` to the drench adapters among
# them as <name as linked>=<precision> and `bullets_out` to the Bullet libraries as <item>=<precision>.
function(_drench_bullet_link_closure target adapters_out bullets_out)
  get_target_property(type ${target} TYPE)
  set(links LINK_LIBRARIES)
  if(type STREQUAL "INTERFACE_LIBRARY")
    set(links INTERFACE_LINK_LIBRARIES)
  endif()
  set(queue "")
  _drench_append_property(queue ${target} ${links} LINK_OPTIONS)
  set(adapters "")
  set(bullets "")
  set(seen "")
  list(LENGTH queue left)
  while(left GREATER 0)
    list(POP_FRONT queue item)
    list(LENGTH queue left)
    if(item MATCHES "^::@")
      continue()  # CMake's marks of the directory an item was linked from
    endif()
    _drench_unwrap_link_item("${item}" item)
    if(item STREQUAL "" OR item IN_LIST seen)
      continue()
    endif()
    list(APPEND seen "${item}")
    if(NOT TARGET "${item}")
      _drench_bullet_library_precision("${item}" precision)
      if(precision)
        list(APPEND bullets "${item}=${precision}")
      endif()
      continue()
    endif()
    set(name "${item}")
    get_target_property(aliased ${item} ALIASED_TARGET)
    if(aliased)
      set(item ${aliased})
    endif()
    get_target_property(precision ${item} DRENCH_BULLET_PRECISION)
    if(precision)
      list(APPEND adapters "${name}=${precision}")
    endif()
    # An imported Bullet library names its file in its location. A Bullet built in the project (its own
    # targets) has no name that tells its precision, and is not judged.
    get_target_property(imported ${item} IMPORTED)
    get_target_property(type ${item} TYPE)
    if(imported AND NOT type STREQUAL "INTERFACE_LIBRARY")
      get_target_property(configurations ${item} IMPORTED_CONFIGURATIONS)
      if(NOT configurations)
        set(configurations "")
      endif()
      set(properties IMPORTED_LOCATION IMPORTED_IMPLIB)
      foreach(configuration IN LISTS configurations)
        string(TOUPPER "${configuration}" configuration)
        list(APPEND properties IMPORTED_LOCATION_${configuration} IMPORTED_IMPLIB_${configuration})
      endforeach()
      _drench_append_property(queue ${item} ${properties})
    endif()
    _drench_append_property(queue ${item} INTERFACE_LINK_LIBRARIES INTERFACE_LINK_OPTIONS)
    list(LENGTH queue left)
  endwhile()
  set(${adapters_out} "${adapters}" PARENT_SCOPE)
  set(${bullets_out} "${bullets}" PARENT_SCOPE)
endfunction()

# Sets `out` to the buildsystem targets of `dir` and its subdirectories.
function(_drench_directory_targets dir out)
  get_property(found DIRECTORY "${dir}" PROPERTY BUILDSYSTEM_TARGETS)
  get_property(subdirectories DIRECTORY "${dir}" PROPERTY SUBDIRECTORIES)
  foreach(subdirectory IN LISTS subdirectories)
    _drench_directory_targets("${subdirectory}" below)
    list(APPEND found ${below})
  endforeach()
  set(${out} "${found}" PARENT_SCOPE)
endfunction()

# The check itself: an error (SEND_ERROR, so the configure fails and generates nothing) for every target that
# would put two Bullet precisions in one program with a drench adapter.
function(drench_check_bullet_precision)
  get_property(wanted GLOBAL PROPERTY DRENCH_WANTED_BULLET_PRECISION)
  get_property(wanted_source GLOBAL PROPERTY DRENCH_WANTED_BULLET_PRECISION_SOURCE)
  _drench_directory_targets("${CMAKE_SOURCE_DIR}" targets)
  foreach(target IN LISTS targets)
    get_target_property(type ${target} TYPE)
    if(type STREQUAL "UTILITY" OR type STREQUAL "GLOBAL_TARGET")
      continue()
    endif()
    _drench_bullet_link_closure(${target} adapters bullets)
    if(NOT adapters)
      continue()
    endif()
    list(GET adapters 0 first)
    string(REGEX REPLACE "=.*" "" adapter "${first}")
    string(REGEX REPLACE ".*=" "" adapter_precision "${first}")
    # What in the program is of another precision than the first adapter it links, and why.
    set(culprits "")
    set(other "")
    foreach(entry IN LISTS adapters bullets)
      string(REGEX REPLACE "=.*" "" what "${entry}")
      string(REGEX REPLACE ".*=" "" precision "${entry}")
      if(NOT precision STREQUAL adapter_precision)
        set(other ${precision})
        list(APPEND culprits "${what}")
      endif()
    endforeach()
    if(culprits)
      list(JOIN culprits ", " culprits)
      if(other STREQUAL "single")
        set(known "FindBullet's BULLET_LIBRARIES and pkg-config's bullet are single precision")
      else()
        set(known "Debian's libraries ending in -float64, pkg-config's bullet-float64, are double precision")
      endif()
      set(problem "together with ${other}-precision Bullet: ${culprits} (${known}). A program with both "
                  "Bullets crashes at start.")
      set(keep "; or drop those and let ${adapter} bring its own Bullet")
    elseif(wanted AND NOT wanted STREQUAL adapter_precision)
      set(other ${wanted})
      set(problem "but this project asks for ${wanted}-precision Bullet (${wanted_source}).")
      set(keep "")
    else()
      continue()
    endif()
    if(TARGET drench::bullet_${other})
      set(fix "Link drench::bullet_${other} instead of ${adapter} (this drench has it)${keep}; or build")
    else()
      set(fix "This drench has no drench::bullet_${other}${keep}; or build")
    endif()
    string(CONCAT message "drench: target '${target}' links ${adapter}, drench's "
                          "${adapter_precision}-precision Bullet adapter (DRENCH_BULLET_PRECISION=${adapter_precision}), " ${problem} " "
                          "${fix} drench with -DDRENCH_BULLET_PRECISION=${other}.")
    message(SEND_ERROR "${message}")
  endforeach()
endfunction()

# Schedules drench_check_bullet_precision once, at the end of the top-level CMakeLists.txt, when every
# target exists (find_package(drench) and add_subdirectory(drench) call it, maybe more than once).
function(drench_defer_bullet_precision_check)
  get_property(scheduled GLOBAL PROPERTY DRENCH_BULLET_PRECISION_CHECK_SCHEDULED)
  if(NOT scheduled)
    set_property(GLOBAL PROPERTY DRENCH_BULLET_PRECISION_CHECK_SCHEDULED ON)
    cmake_language(DEFER DIRECTORY "${CMAKE_SOURCE_DIR}" CALL drench_check_bullet_precision)
  endif()
endfunction()
