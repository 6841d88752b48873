# flowfusion_stage(NAME DEPS ... [PRIVATE_DEPS ...] [PRIVATE_INCLUDES ...] [PRIVATE_DEFINES ...]
#                  [INTERNAL_HEADERS ...]):
# a static library from every .cpp in src/flowfusion/NAME, installed and exported as
# flowfusion::flowfusion_NAME, with the folder's headers under include/flowfusion/NAME except the
# INTERNAL_HEADERS (file names in the folder that only its own sources include; no installed
# header may include one: tests/install checks it).
function(flowfusion_stage name)
  cmake_parse_arguments(ARG "" "" "DEPS;PRIVATE_DEPS;PRIVATE_INCLUDES;PRIVATE_DEFINES;INTERNAL_HEADERS" ${ARGN})
  file(GLOB _headers CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${name}/*.h)
  foreach(_internal ${ARG_INTERNAL_HEADERS})
    if(NOT EXISTS ${CMAKE_CURRENT_SOURCE_DIR}/${name}/${_internal})
      message(FATAL_ERROR "flowfusion_stage(${name}): INTERNAL_HEADERS names ${_internal}, which is not in ${name}/")
    endif()
    list(REMOVE_ITEM _headers ${CMAKE_CURRENT_SOURCE_DIR}/${name}/${_internal})
  endforeach()
  install(FILES ${_headers} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/flowfusion/${name})
  file(GLOB _sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${name}/*.cpp)
  if(_sources)
    add_library(flowfusion_${name} STATIC ${_sources})
    target_include_directories(flowfusion_${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>
                                                         $<INSTALL_INTERFACE:include>)
    target_link_libraries(flowfusion_${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
    target_include_directories(flowfusion_${name} SYSTEM PRIVATE ${ARG_PRIVATE_INCLUDES})
    target_compile_definitions(flowfusion_${name} PRIVATE ${ARG_PRIVATE_DEFINES})
    set_target_properties(flowfusion_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  else()
    # A stage whose folder holds only headers so far.
    add_library(flowfusion_${name} INTERFACE)
    target_include_directories(flowfusion_${name} INTERFACE $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/src>
                                                            $<INSTALL_INTERFACE:include>)
    target_link_libraries(flowfusion_${name} INTERFACE ${ARG_DEPS})
  endif()
  install(TARGETS flowfusion_${name} EXPORT flowfusionTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
endfunction()

# flowfusion_test(STAGE DEPS ... [TEST_PROPERTIES ...]): one GoogleTest executable from every .cpp in
# tests/STAGE; TEST_PROPERTIES are set on each of its tests (e.g. a fixture they need).
function(flowfusion_test stage)
  cmake_parse_arguments(ARG "" "" "DEPS;TEST_PROPERTIES" ${ARGN})
  file(GLOB _sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/${stage}/*.cpp)
  if(NOT _sources)
    return()
  endif()
  add_executable(test_${stage} ${_sources})
  target_link_libraries(test_${stage} PRIVATE flowfusion_testing ${ARG_DEPS} GTest::gtest GTest::gtest_main)
  gtest_discover_tests(test_${stage} DISCOVERY_TIMEOUT 60
    PROPERTIES ENVIRONMENT "FLOWFUSION_SHARED_DATA=${FLOWFUSION_SHARED_DATA}" ${ARG_TEST_PROPERTIES})
endfunction()
