# ctest's tools.consumer_project: installs the build tree into a scratch prefix (install only, nothing
# rebuilt), then configures, builds and runs tests/consumer against it with find_package(weighted_icp), and,
# when the Python module was built, imports it from the installed site-packages.
# cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DSCRATCH=... -DPYTHON=... [-DPYTHON_DIR=lib/...] -P run_consumer_test.cmake
foreach(var BUILD_DIR SOURCE_DIR SCRATCH)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_consumer_test.cmake: -D${var}=... is required")
  endif()
endforeach()

function(run what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "${what} failed (${status}):\n${out}\n${err}")
  endif()
  message(STATUS "${what}: ok")
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

file(REMOVE_RECURSE ${SCRATCH})
set(prefix ${SCRATCH}/prefix)
run("install into ${prefix}" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
if(NOT EXISTS ${prefix}/lib/cmake/weighted_icp/weighted_icpConfigVersion.cmake)
  message(FATAL_ERROR "the install has no lib/cmake/weighted_icp/weighted_icpConfigVersion.cmake")
endif()
run("configure the consumer" ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${SCRATCH}/consumer -G Ninja
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${prefix})
run("build the consumer" ${CMAKE_COMMAND} --build ${SCRATCH}/consumer)
run("run the consumer" ${SCRATCH}/consumer/consumer ${SCRATCH}/map.txt)
message(STATUS "${last_output}")
if(PYTHON AND PYTHON_DIR)
  run("import the installed Python module" ${CMAKE_COMMAND} -E env PYTHONPATH=${prefix}/${PYTHON_DIR}
      ${PYTHON} -c "import weighted_icp, sys; assert weighted_icp.__file__.startswith('${prefix}'), weighted_icp.__file__; print(weighted_icp.__version__)")
  # Loop closure by default reads the package's own vocabulary, installed beside the extension.
  run("close loops with the installed package's vocabulary" ${CMAKE_COMMAND} -E env PYTHONPATH=${prefix}/${PYTHON_DIR}
      ${PYTHON} -c "import weighted_icp; weighted_icp.RgbdSlam('fr1', loop_closure=True)")
endif()
