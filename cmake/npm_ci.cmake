# cmake -DSOURCE=<folder with package.json and package-lock.json> -DDEST=<build folder>
#       -DPURPOSE=<what needs the packages> -P npm_ci.cmake
# Copies SOURCE's files into DEST and installs the packages of the committed lock file there
# (npm ci). Without npm, or when the registry cannot be reached, it says so and the tests that
# need the packages skip; the build goes on. DEST/npm_ci.stamp is written only on success, so a
# failed install is tried again by the next build.
file(MAKE_DIRECTORY ${DEST})
file(GLOB _files LIST_DIRECTORIES false ${SOURCE}/*)
file(COPY ${_files} DESTINATION ${DEST})
find_program(NPM npm)
if(NOT NPM)
  message(WARNING "npm not found: ${PURPOSE} will skip (install nodejs and npm)")
  return()
endif()
execute_process(COMMAND ${NPM} ci --no-audit --no-fund --loglevel=error WORKING_DIRECTORY ${DEST}
                RESULT_VARIABLE result OUTPUT_QUIET)
if(NOT result EQUAL 0)
  file(REMOVE_RECURSE ${DEST}/node_modules)
  message(WARNING "npm ci failed in ${DEST}: ${PURPOSE} will skip")
  return()
endif()
file(TOUCH ${DEST}/npm_ci.stamp)
