# The .vdb files of `engage simulate`, read back with OpenVDB's own vdb_print (Debian
# libopenvdb-tools), for both stock models: removed.vdb holds the grids removed, step and mrr;
# stock.vdb the fractions "stock" (a fog volume) and "surface", a narrow-band level set whose
# background is 3 voxels (0.9 mm at 0.3 mm voxels) and whose values reach it and stay within it.
#   cmake -DENGAGE=... -DVDB_PRINT=... -DPROGRAM=... -DOUT=... -P VdbGrids.cmake
foreach(model voxel dexel)
  set(out ${OUT}/${model})
  file(REMOVE_RECURSE ${out})
  execute_process(COMMAND ${ENGAGE} simulate ${PROGRAM} --tool flat --diameter 6mm
                          --stock box:0,0,-10,60,60,0 --voxel 0.3mm --stock-model ${model}
                          --out ${out} --quiet
                  RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${model}: engage simulate failed (${rc}): ${err}")
  endif()
  execute_process(COMMAND ${VDB_PRINT} -l ${out}/removed.vdb OUTPUT_VARIABLE removed RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${model}: vdb_print could not read removed.vdb")
  endif()
  foreach(name removed step mrr)
    if(NOT removed MATCHES "Name: ${name}\n")
      message(FATAL_ERROR "${model}: removed.vdb has no grid '${name}':\n${removed}")
    endif()
  endforeach()
  execute_process(COMMAND ${VDB_PRINT} -l ${out}/stock.vdb OUTPUT_VARIABLE stock RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${model}: vdb_print could not read stock.vdb")
  endif()
  if(NOT stock MATCHES "Name: stock\n.*class: fog volume")
    message(FATAL_ERROR "${model}: stock.vdb has no fog volume 'stock':\n${stock}")
  endif()
  string(REGEX MATCH "Name: surface\n.*" surface "${stock}")
  if(NOT surface MATCHES "class: level set")
    message(FATAL_ERROR "${model}: stock.vdb has no level set 'surface':\n${stock}")
  endif()
  string(REGEX MATCH "Background value: ([-0-9.e]+)" _ "${surface}")
  set(background ${CMAKE_MATCH_1})
  string(REGEX MATCH "Min value: ([-0-9.e]+)" _ "${surface}")
  set(min ${CMAKE_MATCH_1})
  string(REGEX MATCH "Max value: ([-0-9.e]+)" _ "${surface}")
  set(max ${CMAKE_MATCH_1})
  # The band reaches 3 voxels each side (its extremes within 0.05 mm of them: its deepest value
  # may be a rounding inside, vdb_print's -0.899999) and no value leaves it.
  if(NOT background STREQUAL "0.9" OR min LESS -0.90001 OR min GREATER -0.85
     OR max GREATER 0.90001 OR max LESS 0.85)
    message(FATAL_ERROR "${model}: surface band ${min}..${max}, background ${background}; "
                        "expected -0.9..0.9, background 0.9 (3 voxels of 0.3 mm)")
  endif()
  message(STATUS "${model}: removed.vdb and stock.vdb hold their grids")
endforeach()
