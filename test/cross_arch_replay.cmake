# Replays the bundled frames with the native binary and with the armhf binary under qemu,
# then compares the two odometry logs (test/compare_odometry_logs.cpp states the tolerances).
string(REPLACE "|" ";" EMULATOR "${EMULATOR}")
string(REPLACE "|" ";" ARGS "${ARGS}")  # more options for both replays
file(MAKE_DIRECTORY ${OUT})
foreach(run native armhf)
  if(run STREQUAL native)
    set(cmd ${NATIVE_EXE})
  else()
    set(cmd ${EMULATOR} ${ARMHF_EXE})
  endif()
  execute_process(COMMAND ${cmd} --source ${SOURCE} --config ${CONFIG} --log ${OUT}/${run}.csv -q ${ARGS}
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${run} replay exited ${rc}: ${err}")
  endif()
endforeach()
execute_process(COMMAND ${COMPARE} ${OUT}/native.csv ${OUT}/armhf.csv RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "armhf and native odometry differ beyond floating-point tolerance")
endif()
