# CTest driver (cmake -P): `quijibo-mpi sweep` on NP ranks over a grid of slices of a small map;
# every job runs, in its own folder, and index.json lists them.
# -D QUIJIBO= QUIJIBO_MPI= MPIEXEC= NP= DIR=
file(REMOVE_RECURSE ${DIR})
file(MAKE_DIRECTORY ${DIR})
set(ENV{OMP_NUM_THREADS} 1)
execute_process(COMMAND ${QUIJIBO} -q map random --top 6 --bottom 4 --seed 3 --center-on sphere
                        --target-resolution 12 -o ${DIR}/map.json RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "map random failed")
endif()
file(WRITE ${DIR}/sweep.json "{
  \"out\": \"${DIR}/results\",
  \"args\": [\"mesh\", \"${DIR}/map.json\", \"-o\", \"{dir}/mesh.ply\", \"-r\", \"24\", \"-n\", \"2\",
           \"--slice\", \"{slice}\", \"--translate\", \"{tx},0,0\"],
  \"grid\": {\"slice\": [0.0, 0.1], \"tx\": [0.0, 0.05]},
  \"jobs\": [{\"name\": \"fails\", \"args\": [\"mesh\", \"${DIR}/missing.json\", \"-o\", \"{dir}/x.ply\"]}]
}")
execute_process(COMMAND ${MPIEXEC} --allow-run-as-root --oversubscribe -np ${NP} ${QUIJIBO_MPI} -q sweep ${DIR}/sweep.json
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(rc EQUAL 0)
  message(FATAL_ERROR "the sweep should report its failed job:\n${out}\n${err}")
endif()
file(READ ${DIR}/results/index.json index)
string(JSON njobs LENGTH "${index}" jobs)
string(JSON failed GET "${index}" failed)
if(NOT njobs EQUAL 5 OR NOT failed EQUAL 1)
  message(FATAL_ERROR "expected 5 jobs, 1 failed:\n${index}")
endif()
foreach(i RANGE 0 3)
  string(JSON name GET "${index}" jobs ${i} name)
  string(JSON code GET "${index}" jobs ${i} exit_code)
  if(NOT code EQUAL 0 OR NOT EXISTS ${DIR}/results/${name}/mesh.ply)
    message(FATAL_ERROR "job ${name}: exit ${code}, or no mesh.ply\n${index}")
  endif()
endforeach()
message(STATUS "sweep: 5 jobs on ${NP} ranks, index.json complete")
file(REMOVE_RECURSE ${DIR})
