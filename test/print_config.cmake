# rgbd-odometry --print-config, end to end through the binary: the printout names every key
# and --config reads it back to the same printout (EMULATOR runs an armhf binary; its
# arguments joined by "|").
string(REPLACE "|" ";" emulator "${EMULATOR}")
execute_process(COMMAND ${emulator} ${EXE} --print-config --config ${CONFIG} --set "link.ekf_origin=47.397742, 8.545594, 488"
                OUTPUT_FILE ${OUT}.yaml RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "--print-config failed: ${rc}")
endif()
file(STRINGS ${OUT}.yaml lines REGEX "^ *[a-z_0-9]+: ")
list(LENGTH lines keys)
if(keys LESS 60)
  message(FATAL_ERROR "--print-config printed ${keys} keys, expected every one (60 or more)")
endif()
execute_process(COMMAND ${emulator} ${EXE} --print-config --config ${OUT}.yaml OUTPUT_FILE ${OUT}.again.yaml RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "--config did not take the printout back: ${rc}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files ${OUT}.yaml ${OUT}.again.yaml RESULT_VARIABLE differ)
if(differ)
  message(FATAL_ERROR "the printout read back prints differently: ${OUT}.yaml ${OUT}.again.yaml")
endif()
message(STATUS "${keys} keys printed, read back to the same printout")
