# The layer check's own test (cmake -P): on a copy of the real module graph it passes the real
# tree, and fails, naming the file and the module, when a low module includes a higher one's
# header.
foreach(v DATA SOURCE WORK)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "run.cmake needs -D${v}=...")
  endif()
endforeach()
set(check ${SOURCE}/cmake/check_layers.cmake)
execute_process(COMMAND ${CMAKE_COMMAND} -DDATA=${DATA} -DROOT=${SOURCE} -DSTAMP=${WORK}/ok.stamp
                -P ${check} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the real tree fails the layer check:\n${err}")
endif()
# A tree whose path module includes the force module's header.
file(REMOVE_RECURSE ${WORK}/tree)
file(MAKE_DIRECTORY ${WORK}/tree/src/path ${WORK}/tree/include/trochomill)
file(WRITE ${WORK}/tree/src/path/wrong.cpp "#include \"trochomill/path.hpp\"\n#include \"trochomill/force.hpp\"\n")
execute_process(COMMAND ${CMAKE_COMMAND} -DDATA=${DATA} -DROOT=${WORK}/tree
                -DSTAMP=${WORK}/wrong.stamp -P ${check} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "src/path/wrong.cpp: includes \"trochomill/force.hpp\" \\(module force\\)")
  message(FATAL_ERROR "a wrong-way include passed the layer check (rc ${rc}):\n${err}")
endif()
message(STATUS "the layer check refuses src/path -> force")
# A module's further public headers (include/trochomill/<module>/) belong to it too.
file(WRITE ${WORK}/tree/src/path/wrong.cpp "#include \"trochomill/sim/dexel.hpp\"\n")
execute_process(COMMAND ${CMAKE_COMMAND} -DDATA=${DATA} -DROOT=${WORK}/tree
                -DSTAMP=${WORK}/wrong2.stamp -P ${check} RESULT_VARIABLE rc ERROR_VARIABLE err)
if(rc EQUAL 0 OR NOT err MATCHES "src/path/wrong.cpp: includes \"trochomill/sim/dexel.hpp\" \\(module sim\\)")
  message(FATAL_ERROR "an include of sim/dexel.hpp from path passed the layer check (rc ${rc}):\n${err}")
endif()
message(STATUS "the layer check refuses src/path -> sim/dexel.hpp")
