# Replays the bundled frames once per kernel set this build has (RGBDO_KERNELS=SET), as a user
# forcing a set would, and compares each odometry log with the first set's
# (test/compare_odometry_logs.cpp states the tolerances; the x86 sets agree bit for bit, the
# NEON divide/sqrt to a few ulp). A set this CPU cannot run is refused by the program (exit
# 2, naming the set) and left out here, saying so.
string(REPLACE "|" ";" EMULATOR "${EMULATOR}")
string(REPLACE "|" ";" SETS "${SETS}")
file(MAKE_DIRECTORY ${OUT})
set(reference "")
foreach(set IN LISTS SETS)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env RGBDO_KERNELS=${set}
                          ${EMULATOR} ${EXE} --source ${SOURCE} --config ${CONFIG} --log ${OUT}/${set}.csv -q
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(rc EQUAL 2 AND err MATCHES "this CPU cannot run that set")
    message(STATUS "kernel set ${set}: not supported by this CPU, not compared")
    continue()
  endif()
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "replay with RGBDO_KERNELS=${set} exited ${rc}: ${err}")
  endif()
  if(reference STREQUAL "")
    set(reference ${set})
    continue()
  endif()
  execute_process(COMMAND ${EMULATOR} ${COMPARE} ${OUT}/${reference}.csv ${OUT}/${set}.csv RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the odometry with kernel set ${set} differs from ${reference}'s beyond floating-point tolerance")
  endif()
  message(STATUS "kernel set ${set}: same odometry as ${reference}")
endforeach()
if(reference STREQUAL "")
  message(FATAL_ERROR "no kernel set could run")
endif()
