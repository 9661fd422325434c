# ctest's `downstream` test (tests/CMakeLists.txt): installs the build BUILD_DIR into
# WORK_DIR/prefix, then configures, builds and runs this directory's project against it
# with -DCMAKE_PREFIX_PATH=WORK_DIR/prefix, as a project outside the tree would.
foreach(_v BUILD_DIR SOURCE_DIR WORK_DIR GENERATOR CXX)
  if(NOT DEFINED ${_v})
    message(FATAL_ERROR "run.cmake needs -D${_v}=...")
  endif()
endforeach()

function(step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "downstream: failed (${rc}): ${cmd}")
  endif()
endfunction()

string(REPLACE "|" ";" PREFIX_PATH "${PREFIX_PATH}")
file(REMOVE_RECURSE ${WORK_DIR})
step(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix)
# The dependencies are found where the library's own build found them (PREFIX_PATH).
step(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release
     -DCMAKE_CXX_COMPILER=${CXX} "-DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix;${PREFIX_PATH}")
step(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
step(${WORK_DIR}/build/downstream ${WORK_DIR}/camchain.yaml)
