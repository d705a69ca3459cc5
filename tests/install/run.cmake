# The install test (cmake -P): installs the build tree into a fresh prefix, configures and
# builds the consumer project against it with find_package(trochomill), and checks that the
# consumer's plan of an example is the CLI's (same cycles and path length).
foreach(v BUILD SOURCE WORK CXX)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "run.cmake needs -D${v}=...")
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK})
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()
run(${CMAKE_COMMAND} --install ${BUILD} --prefix ${WORK}/prefix)
run(${CMAKE_COMMAND} -S ${SOURCE}/tests/install/consumer -B ${WORK}/build -G Ninja
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=${WORK}/prefix -DCMAKE_CXX_COMPILER=${CXX} "-DCMAKE_CXX_FLAGS=${FLAGS}"
    "-DCMAKE_EXE_LINKER_FLAGS=${FLAGS}")
run(${CMAKE_COMMAND} --build ${WORK}/build)
set(example ${SOURCE}/examples/wagih2023/elliptical.toml)
run(${WORK}/build/consumer ${example})
set(consumer "${out}")
run(${WORK}/prefix/bin/trochomill plan ${example} -o ${WORK}/slot.ngc)
string(REGEX MATCH "[0-9]+ cycles, path [0-9.]+ mm" cli "${out}")
string(STRIP "${consumer}" consumer)
if(NOT consumer STREQUAL cli OR cli STREQUAL "")
  message(FATAL_ERROR "the consumer printed '${consumer}', the installed CLI '${cli}'")
endif()
message(STATUS "consumer built against the installed tree: ${consumer}")

# The plugins (docs/architecture.md, "Plugins") are installed beside the library, and the
# installed CLI runs a two-goal optimisation (pagmo's NSGA-II) and writes a mesh (assimp) with
# them.
set(plugins nsga2 rows hdf5 assimp ceres sndfile)
if(MPI)
  list(APPEND plugins mpi)
endif()
foreach(name IN LISTS plugins)
  file(GLOB_RECURSE plugin "${WORK}/prefix/*/trochomill/libtrochomill_${name}.so")
  if(NOT plugin)
    message(FATAL_ERROR "libtrochomill_${name}.so is not in the installed tree")
  endif()
endforeach()
run(${WORK}/prefix/bin/trochomill insert ${example} -o ${WORK}/insert.stl)
if(NOT EXISTS ${WORK}/insert.stl)
  message(FATAL_ERROR "the installed CLI wrote no insert mesh")
endif()
run(${WORK}/prefix/bin/trochomill optimize ${example} --var path.step=0.5:1
    --maximize cycle_mrr_mm3_per_min --minimize h_max_mm --max-evals 16 --population 8
    --pareto ${WORK}/pareto.csv)
file(STRINGS ${WORK}/pareto.csv pareto)
list(LENGTH pareto rows)
if(rows LESS 2)
  message(FATAL_ERROR "the installed CLI's Pareto set is empty: ${pareto}")
endif()
message(STATUS "the installed CLI's two-goal optimisation: ${rows} lines of Pareto set")

# The installed Python package (when built): imported from the prefix's site-packages alone,
# it plans the same slot.
if(DEFINED PYTHON AND DEFINED PYTHON_DIR)
  execute_process(
    COMMAND ${CMAKE_COMMAND} -E env PYTHONPATH=${WORK}/prefix/${PYTHON_DIR} ${PYTHON} -c
      "import sys, trochomill as tm; assert tm.__file__.startswith(sys.argv[2]), tm.__file__; p = tm.plan(tm.Job.from_toml(sys.argv[1])); print(f'{p.cycles} cycles, path {p.length_mm:.3f} mm')"
      ${example} ${WORK}/prefix
    RESULT_VARIABLE rc OUTPUT_VARIABLE py ERROR_VARIABLE err WORKING_DIRECTORY ${WORK})
  string(STRIP "${py}" py)
  if(NOT rc EQUAL 0 OR NOT py STREQUAL cli)
    message(FATAL_ERROR "the installed Python package printed '${py}' (${rc}), the CLI '${cli}'\n${err}")
  endif()
  message(STATUS "the installed Python package: ${py}")
endif()
