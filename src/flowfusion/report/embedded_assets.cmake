# What the report page is made of, compiled into flowfusion_report as string constants
# (embedded_assets.h) so that a report never depends on what is installed where it is opened:
# the page's own HTML, CSS and script (report/assets/, linted by ESLint: tests/lint) and the
# JavaScript libraries from Debian's libjs-three. Included from src/flowfusion/CMakeLists.txt after
# flowfusion_stage(report ...).
set(FLOWFUSION_THREE_JS_DIR "/usr/share/javascript/three" CACHE PATH "Folder of Debian's libjs-three")
set(_three_js "${FLOWFUSION_THREE_JS_DIR}/three.min.js")
set(_orbit_js "${FLOWFUSION_THREE_JS_DIR}/examples/js/controls/OrbitControls.js")
foreach(_file ${_three_js} ${_orbit_js})
  if(NOT EXISTS "${_file}")
    message(FATAL_ERROR "${_file} is missing: install Debian's libjs-three (scripts/install-deps.sh)")
  endif()
endforeach()
set(_assets ${CMAKE_CURRENT_SOURCE_DIR}/report/assets)
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${_three_js} ${_orbit_js}
             ${_assets}/report.html ${_assets}/report.css ${_assets}/report.js)

file(READ "${_three_js}" FLOWFUSION_THREE_JS)
file(READ "${_orbit_js}" FLOWFUSION_ORBIT_JS)
file(READ "${_assets}/report.html" FLOWFUSION_REPORT_HTML)
file(READ "${_assets}/report.css" FLOWFUSION_REPORT_CSS)
file(READ "${_assets}/report.js" FLOWFUSION_REPORT_JS)
foreach(_text FLOWFUSION_THREE_JS FLOWFUSION_ORBIT_JS FLOWFUSION_REPORT_HTML FLOWFUSION_REPORT_CSS FLOWFUSION_REPORT_JS)
  string(FIND "${${_text}}" ")ffasset\"" _clash)
  if(NOT _clash EQUAL -1)
    message(FATAL_ERROR "the raw-string delimiter ffasset occurs in an embedded file; change it in embedded_assets.cpp.in")
  endif()
endforeach()
configure_file(${CMAKE_CURRENT_SOURCE_DIR}/report/embedded_assets.cpp.in
  ${CMAKE_CURRENT_BINARY_DIR}/report/embedded_assets.cpp @ONLY)
target_sources(flowfusion_report PRIVATE ${CMAKE_CURRENT_BINARY_DIR}/report/embedded_assets.cpp)
