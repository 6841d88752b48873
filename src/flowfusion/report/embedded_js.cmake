# The report's JavaScript libraries, from Debian's libjs-three, compiled into flowfusion_report
# as string constants (embedded_js.h) so that a report never depends on what is installed where it
# is opened. Included from src/flowfusion/CMakeLists.txt after flowfusion_stage(report ...).
set(FLOWFUSION_THREE_JS_DIR "/usr/share/javascript/three" CACHE PATH "Folder of Debian's libjs-three")
set(_three_js "${FLOWFUSION_THREE_JS_DIR}/three.min.js")
set(_orbit_js "${FLOWFUSION_THREE_JS_DIR}/examples/js/controls/OrbitControls.js")
foreach(_file ${_three_js} ${_orbit_js})
  if(NOT EXISTS "${_file}")
    message(FATAL_ERROR "${_file} is missing: install Debian's libjs-three (scripts/install-deps.sh)")
  endif()
endforeach()
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${_three_js} ${_orbit_js})

file(READ "${_three_js}" FLOWFUSION_THREE_JS)
file(READ "${_orbit_js}" FLOWFUSION_ORBIT_JS)
foreach(_text FLOWFUSION_THREE_JS FLOWFUSION_ORBIT_JS)
  string(FIND "${${_text}}" ")ffjs\"" _clash)
  if(NOT _clash EQUAL -1)
    message(FATAL_ERROR "the raw-string delimiter ffjs occurs in the embedded JavaScript; change it in embedded_js.cpp.in")
  endif()
endforeach()
configure_file(${CMAKE_CURRENT_SOURCE_DIR}/report/embedded_js.cpp.in
  ${CMAKE_CURRENT_BINARY_DIR}/report/embedded_js.cpp @ONLY)
target_sources(flowfusion_report PRIVATE ${CMAKE_CURRENT_BINARY_DIR}/report/embedded_js.cpp)
