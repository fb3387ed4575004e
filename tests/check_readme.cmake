cmake_minimum_required(VERSION 3.22)
# The README is for a newcomer who reads it in five minutes (issue 24): under 10,000 characters, with
# measurements in docs/performance.md and docs/accuracy.md, and every document it links present.
# Run by ctest as `cmake -DSOURCE_DIR=<repo> -P check_readme.cmake`.

file(READ "${SOURCE_DIR}/README.md" readme)
string(LENGTH "${readme}" length)
if(length GREATER_EQUAL 10000)
  message(FATAL_ERROR "README.md has ${length} characters, the limit is 10,000: move measurements to "
                      "docs/performance.md or docs/accuracy.md")
endif()
# Walk the "](target)" links by position: CMake lists do not split inside square brackets, so a list of
# regex matches over Markdown would not hold one link per element.
set(rest "${readme}")
while(TRUE)
  string(FIND "${rest}" "](" at)
  if(at EQUAL -1)
    break()
  endif()
  math(EXPR start "${at} + 2")
  string(SUBSTRING "${rest}" ${start} -1 rest)
  string(FIND "${rest}" ")" end)
  string(SUBSTRING "${rest}" 0 ${end} path)
  string(REGEX REPLACE "#.*$" "" path "${path}")
  if(NOT path MATCHES "^https?:" AND NOT EXISTS "${SOURCE_DIR}/${path}")
    message(FATAL_ERROR "README.md links to ${path}, which does not exist")
  endif()
endwhile()
message(STATUS "check_readme: README.md has ${length} characters and its links resolve")
