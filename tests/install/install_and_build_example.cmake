# cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... -DAPP=... -P install_and_build_example.cmake
# Installs the build into a fresh prefix, builds examples/cpp against it alone and runs it on a
# small synthetic sequence: the installed package must be complete and usable.
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(OUTPUT "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${WORK_DIR})
set(PREFIX ${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${PREFIX})
foreach(f include/flowfusion/flowfusion.h include/flowfusion/pipeline/flowfusion_system.h
          lib/cmake/flowfusion/flowfusionConfig.cmake lib/cmake/flowfusion/flowfusionTargets.cmake bin/flowfusion)
  if(NOT EXISTS ${PREFIX}/${f})
    message(FATAL_ERROR "the install lacks ${f}")
  endif()
endforeach()
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/cpp -B ${WORK_DIR}/build -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_PREFIX_PATH=${PREFIX})
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${PREFIX}/bin/flowfusion synth ${WORK_DIR}/seq --frames 5 --width 160 --height 120)
run(${WORK_DIR}/build/print_poses ${WORK_DIR}/seq)
string(REGEX MATCHALL "\n" lines "${OUTPUT}")
list(LENGTH lines n)
if(NOT n EQUAL 5)
  message(FATAL_ERROR "print_poses printed ${n} poses for 5 frames:\n${OUTPUT}")
endif()
message(STATUS "the example built against ${PREFIX} printed ${n} poses")
