# A second sensor end to end: ICL-NUIM's rendered frames (exact depth, colour and depth taken
# together) through the binary with its shipped configuration, deploy/config/icl-nuim.yaml.
# What the program learns of a sensor must come out as this one is, and its accuracy must stay
# that of exact depth: measured on the 40 bundled frames (x86-64), pair RPE 0.117 mm and
# 0.003 deg, 1-s rotation drift 0.015 deg/s, the depth's lag learnt as -0.9 ms, its noise as
# 0.038e-3 Z^2, and the depth alignment fused into every pair. EMULATOR runs an armhf binary
# (its arguments joined by "|").
string(REPLACE "|" ";" emulator "${EMULATOR}")
execute_process(COMMAND ${emulator} ${EXE} --source ${SOURCE} --config ${CONFIG} -q --groundtruth-allowance none
                OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbd-odometry exited ${rc}: ${stderr}")
endif()

function(summary_number pattern name out)
  if(NOT stdout MATCHES "${pattern}")
    message(FATAL_ERROR "the summary has no ${name}:\n${stdout}")
  endif()
  set(${out} "${CMAKE_MATCH_1}" PARENT_SCOPE)
endfunction()

if(NOT stdout MATCHES "39 pairs, 39 ok, 0 failed")
  message(FATAL_ERROR "pairs failed:\n${stdout}")
endif()
if(NOT stdout MATCHES "depth alignment: fused into 39 of 39 good pairs")
  message(FATAL_ERROR "the depth alignment was not fused into every pair:\n${stdout}")
endif()
summary_number("frame-to-frame RPE, translation +RMSE ([0-9.]+)" "pair translation RPE" translation)
summary_number("frame-to-frame RPE, rotation +RMSE ([0-9.]+)" "pair rotation RPE" rotation)
summary_number("drift over 1 s windows, rotation +RMSE ([0-9.]+)" "1-s rotation drift" drift)
summary_number("depth noise ([0-9.]+)e-3 Z\\^2" "learnt depth noise" noise)
summary_number("depth (-?[0-9.]+) ms behind the colour" "learnt depth lag" lag)
if(translation GREATER 0.15 OR rotation GREATER 0.004 OR drift GREATER 0.019)
  message(FATAL_ERROR "ICL-NUIM: pair RPE ${translation} mm, ${rotation} deg, 1-s rotation drift ${drift} deg/s; "
                      "measured 0.117, 0.003, 0.015")
endif()
if(noise GREATER 0.05 OR lag LESS -3 OR lag GREATER 3)
  message(FATAL_ERROR "ICL-NUIM learnt as depth noise ${noise}e-3 Z^2 and a depth lag of ${lag} ms; "
                      "its depth is exact and taken with the colour (measured 0.038e-3, -0.9 ms)")
endif()
