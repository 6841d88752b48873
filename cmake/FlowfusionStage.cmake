# flowfusion_stage(NAME DEPS ... [PRIVATE_DEPS ...] [PRIVATE_INCLUDES ...] [PRIVATE_DEFINES ...]):
# a static library from every .cpp in src/flowfusion/NAME, installed and exported as
# flowfusion::flowfusion_NAME.
function(flowfusion_stage name)
  cmake_parse_arguments(ARG "" "" "DEPS;PRIVATE_DEPS;PRIVATE_INCLUDES;PRIVATE_DEFINES" ${ARGN})
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
