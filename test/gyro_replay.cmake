# Replays with a gyro (imu.txt, made from the recordings' ground truth by
# ../shared/tools/imu-from-groundtruth/make_imu.py: 50 Hz, 0.005 rad/s noise, a bias): the
# capture latency is measured and every motion restamped at its capture instant. Measured on the
# bundled frames (x86-64): fr1's Kinect 16.7 ms (its stamps: the rotations match the motion
# capture 13.6 ms before them; restamped, 0.7 ms), pair rotation error 0.288 -> 0.174 deg; the
# same gyro stamped 30 ms early, 46.7 ms; ICL-NUIM's rendered frames, stamped when taken, nothing
# applied and nothing changed. On fr1 the image shift is moved to the capture instants as well. A
# gyro file beside rgb.txt is read without --imu; a malformed one is refused naming its line.
# EMULATOR runs an armhf binary (its arguments joined by "|").
string(REPLACE "|" ";" emulator "${EMULATOR}")
file(REMOVE_RECURSE "${OUT}")
file(MAKE_DIRECTORY "${OUT}")

function(replay source config imu out_stdout out_stderr)
  set(imu_args)
  if(imu)
    set(imu_args --imu ${imu})
  endif()
  execute_process(COMMAND ${emulator} ${EXE} --source tum:${source} --config ${config} -q ${imu_args} ${ARGN}
                  OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "rgbd-odometry exited ${rc}: ${stderr}")
  endif()
  set(${out_stdout} "${stdout}" PARENT_SCOPE)
  set(${out_stderr} "${stderr}" PARENT_SCOPE)
endfunction()

function(number_in text pattern name out)
  if(NOT text MATCHES "${pattern}")
    message(FATAL_ERROR "no ${name} in:\n${text}")
  endif()
  set(${out} "${CMAKE_MATCH_1}" PARENT_SCOPE)
endfunction()

set(latency_pattern "capture latency (-?[0-9.]+) \\+- [0-9.]+ ms against the gyro")
set(offset_pattern "the rotations \\(colour\\): best with the frames taken (-?[0-9.]+) ")
set(rotation_pattern "frame-to-frame RPE, rotation +RMSE ([0-9.]+)")

# fr1: measured, applied, and the log's times the capture instants.
replay(${FR1} ${FR1_CONFIG} ${IMU_DIR}/fr1_xyz.txt out err)
number_in("${out}" "${latency_pattern}" "latency" latency)
number_in("${out}" "${offset_pattern}" "time offset of the log" offset)
number_in("${out}" "${rotation_pattern}" "pair rotation error" rotation)
if(latency LESS 14.5 OR latency GREATER 18.5)
  message(FATAL_ERROR "fr1's Kinect: capture latency ${latency} ms against the gyro (measured 16.7)")
endif()
if(offset GREATER 4.0 OR offset LESS -3.0)
  message(FATAL_ERROR "the log's times are ${offset} ms from the motion capture's (measured 0.7; the stamps 13.6)")
endif()
if(rotation GREATER 0.19)
  message(FATAL_ERROR "pair rotation error at the log's times ${rotation} deg (measured 0.174; at the stamps 0.288)")
endif()
# Restamped, a pair's image shift is off by the latency applied times its change
# (pipeline/latency_covariance.hpp), which the covariance carries: measured pair NEES 6.94 (87.2 %
# under the gate), 7.90 (82.1 %) without that term, 8.30 at the stamps without the gyro.
number_in("${out}" "joint 6-D NEES per pair \\([0-9]+\\): mean ([0-9.]+)" "pair NEES" nees)
if(nees GREATER 7.4 OR nees LESS 5.2)
  message(FATAL_ERROR "pair NEES ${nees} with the gyro (measured 6.94; 7.90 without the image shift's term)")
endif()
if(NOT out MATCHES "autopilot settings: PX4 EKF2_EV_DELAY 0 ms")
  message(FATAL_ERROR "no autopilot settings in the summary:\n${out}")
endif()
# The image shift, the colour's own and on its stamps on fr1's Kinect, is moved to the capture
# instants (pipeline/depth_clock.hpp): the sideways translations err less, the rotations the
# same. Measured on these 40 frames: moved 7.4 ms, translation RPE 3.967 mm against 4.133 with
# latency.retime_image_shift=false (on all 240 frames 3.40 against 3.80).
set(translation_pattern "frame-to-frame RPE, translation +RMSE ([0-9.]+)")
number_in("${out}" "image shift moved (-?[0-9.]+) ms" "image shift moved" moved)
number_in("${out}" "${translation_pattern}" "pair translation error" translation)
replay(${FR1} ${FR1_CONFIG} ${IMU_DIR}/fr1_xyz.txt kept err --set latency.retime_image_shift=false)
number_in("${kept}" "${translation_pattern}" "pair translation error" kept_translation)
number_in("${kept}" "${rotation_pattern}" "pair rotation error" kept_rotation)
if(moved LESS 4.0 OR moved GREATER 11.0 OR NOT translation LESS kept_translation OR NOT rotation EQUAL kept_rotation
   OR NOT kept MATCHES "its image shift moved 0.0 ms")
  message(FATAL_ERROR "image shift moved ${moved} ms (measured 7.4): translation error ${translation} mm, "
                      "${kept_translation} without (measured 3.967, 4.133); rotation ${rotation}, ${kept_rotation} deg")
endif()

# The same gyro stamped 30 ms early: the latency found moves by as much (tenths of a ms: the
# summary prints one decimal).
replay(${FR1} ${FR1_CONFIG} ${IMU_DIR}/fr1_xyz_shift30.txt out err)
number_in("${out}" "${latency_pattern}" "latency" shifted)
string(REPLACE "." "" shifted_tenths "${shifted}")
string(REPLACE "." "" latency_tenths "${latency}")
math(EXPR moved "${shifted_tenths} - ${latency_tenths}")
if(moved LESS 285 OR moved GREATER 315)
  message(FATAL_ERROR "a gyro stamped 30 ms early moved the latency from ${latency} to ${shifted} ms (measured 30.0 apart)")
endif()

# ICL-NUIM, stamped when taken: nothing to apply, nothing changed.
replay(${ICL} ${ICL_CONFIG} "" plain err)
replay(${ICL} ${ICL_CONFIG} ${IMU_DIR}/icl_office_kt3.txt out err)
number_in("${plain}" "${rotation_pattern}" "pair rotation error" plain_rotation)
number_in("${out}" "${rotation_pattern}" "pair rotation error" rotation)
if(NOT rotation EQUAL plain_rotation OR NOT out MATCHES "applied 0.0 ms")
  message(FATAL_ERROR "ICL-NUIM with a gyro: rotation error ${rotation} deg (without ${plain_rotation}):\n${out}")
endif()

# The recording's own imu.txt is read without --imu; a malformed one is refused by its line.
file(COPY ${ICL}/ DESTINATION ${OUT}/icl)
file(COPY ${IMU_DIR}/icl_office_kt3.txt DESTINATION ${OUT}/icl)
file(RENAME ${OUT}/icl/icl_office_kt3.txt ${OUT}/icl/imu.txt)
replay(${OUT}/icl ${ICL_CONFIG} "" out err)
if(NOT err MATCHES "measured against the gyro of '[^']*/icl/imu.txt' \\(87 samples, 50.0 Hz\\)")
  message(FATAL_ERROR "the recording's imu.txt was not read:\n${err}")
endif()
file(APPEND ${OUT}/icl/imu.txt "5.0 0.1 0.2 fast\n")
execute_process(COMMAND ${emulator} ${EXE} --source tum:${OUT}/icl --config ${ICL_CONFIG} -q
                OUTPUT_VARIABLE out ERROR_VARIABLE err RESULT_VARIABLE rc)
if(NOT rc EQUAL 1 OR NOT err MATCHES "imu.txt:89: bad angular rate 'fast'")
  message(FATAL_ERROR "a malformed imu.txt: exit ${rc}, ${err}")
endif()
