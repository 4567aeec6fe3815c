# CTest driver (cmake -P): a small random map meshed by `quijibo mesh` and by `quijibo-mpi mesh` on NP
# ranks must give the same mesh after canonical sorting, and the same .vdb bytes (but the file UUID);
# streamed (--stream), the same PLY bytes on NP ranks, 1 rank and in one process.
# -D QUIJIBO= QUIJIBO_MPI= CANON= MPIEXEC= NP= DIR=
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
endfunction()
file(REMOVE_RECURSE ${DIR})
file(MAKE_DIRECTORY ${DIR})
set(ENV{OMP_NUM_THREADS} 1)
run(${QUIJIBO} -q map random --top 6 --bottom 4 --seed 3 --center-on sphere --target-resolution 12 -o ${DIR}/map.json)
# 128 cells: the sparse search is on (stride 2), so its lattice is spread over the ranks too.
set(OPTS -r 128 -n 2 --tile 16 --frame fractal)
run(${QUIJIBO} -q mesh ${DIR}/map.json -o ${DIR}/one.ply --vdb ${DIR}/one.vdb ${OPTS} --summary ${DIR}/one.json)
run(${MPIEXEC} --allow-run-as-root --oversubscribe -np ${NP} ${QUIJIBO_MPI} -q mesh ${DIR}/map.json -o ${DIR}/mpi.ply
    --vdb ${DIR}/mpi.vdb ${OPTS} --summary ${DIR}/mpi.json)
run(${CANON} ${DIR}/one.ply ${DIR}/one.bin)
run(${CANON} ${DIR}/mpi.ply ${DIR}/mpi.bin)
file(SIZE ${DIR}/one.bin size)
if(size LESS 1000)
  message(FATAL_ERROR "the reference mesh is nearly empty (${size} bytes)")
endif()
run(${CMAKE_COMMAND} -E compare_files ${DIR}/one.bin ${DIR}/mpi.bin)
# OpenVDB writes a random file UUID into the header (bytes 17..52): compare everything after it.
file(READ ${DIR}/one.vdb vdb1 HEX)
file(READ ${DIR}/mpi.vdb vdb2 HEX)
string(SUBSTRING "${vdb1}" 128 -1 vdb1)
string(SUBSTRING "${vdb2}" 128 -1 vdb2)
if(NOT vdb1 STREQUAL vdb2)
  message(FATAL_ERROR "the .vdb files differ (after the header's UUID)")
endif()
# Streamed on NP ranks (rank 0 writes the pieces as they arrive): the same PLY bytes as `quijibo mesh`
# in memory, and the same .vdb field grid as the in-memory one.
run(${QUIJIBO} -q mesh ${DIR}/map.json -o ${DIR}/field.ply --vdb ${DIR}/field.vdb --vdb-grids field ${OPTS}
    --summary ${DIR}/field.json)
run(${MPIEXEC} --allow-run-as-root --oversubscribe -np ${NP} ${QUIJIBO_MPI} -q mesh ${DIR}/map.json -o ${DIR}/stream.ply
    --stream --vdb ${DIR}/stream.vdb --vdb-grids field ${OPTS} --summary ${DIR}/stream.json)
run(${CMAKE_COMMAND} -E compare_files ${DIR}/one.ply ${DIR}/stream.ply)
# And `quijibo mesh --stream`, and (once, with NP 2) quijibo-mpi on 1 rank: the same bytes again.
run(${QUIJIBO} -q mesh ${DIR}/map.json -o ${DIR}/stream1.ply --stream ${OPTS})
run(${CMAKE_COMMAND} -E compare_files ${DIR}/stream.ply ${DIR}/stream1.ply)
if(NP EQUAL 2)
  run(${MPIEXEC} --allow-run-as-root --oversubscribe -np 1 ${QUIJIBO_MPI} -q mesh ${DIR}/map.json
      -o ${DIR}/rank1.ply --stream ${OPTS})
  run(${CMAKE_COMMAND} -E compare_files ${DIR}/stream.ply ${DIR}/rank1.ply)
endif()
file(READ ${DIR}/field.vdb vdb1 HEX)
file(READ ${DIR}/stream.vdb vdb2 HEX)
string(SUBSTRING "${vdb1}" 128 -1 vdb1)
string(SUBSTRING "${vdb2}" 128 -1 vdb2)
if(NOT vdb1 STREQUAL vdb2)
  message(FATAL_ERROR "the streamed .vdb field grid differs (after the header's UUID)")
endif()
file(READ ${DIR}/one.json one_json)
file(READ ${DIR}/stream.json stream_json)
foreach(key vertices triangles components open_edges specks_removed)
  string(JSON a GET "${one_json}" ${key})
  string(JSON b GET "${stream_json}" ${key})
  if(NOT a EQUAL b)
    message(FATAL_ERROR "streamed summary: ${key} ${b}, in memory ${a}")
  endif()
endforeach()
message(STATUS "np ${NP}: canonical meshes identical (${size} bytes), .vdb identical; streamed PLY (NP ranks, 1 rank, quijibo) and .vdb identical")
file(REMOVE_RECURSE ${DIR})
