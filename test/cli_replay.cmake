# Runs the documented command line on the bundled frames and checks what it promises:
# exit 0, one log row per colour-frame pair in the documented format, one trajectory line
# per frame, and the accuracy summary.
file(MAKE_DIRECTORY ${OUT})
string(REPLACE "|" ";" EMULATOR "${EMULATOR}")
execute_process(
  COMMAND ${EMULATOR} ${EXE} --source ${SOURCE} --config ${CONFIG} --log ${OUT}/odometry.csv --trajectory ${OUT}/trajectory.txt
  RESULT_VARIABLE rc OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbd-odometry exited ${rc}: ${stderr}")
endif()
file(STRINGS ${OUT}/odometry.csv rows)
list(LENGTH rows n_rows)
if(NOT n_rows EQUAL 40)  # header + 39 pairs of the 40 bundled frames
  message(FATAL_ERROR "odometry.csv has ${n_rows} lines, expected 40")
endif()
list(GET rows 0 header)
if(NOT header MATCHES "^t_prev,t_curr,status,inliers,tx,ty,tz,qx,qy,qz,qw,c00,c01,.*,c55,chain,pc00,pc01,.*,pc55$")
  message(FATAL_ERROR "bad header: ${header}")
endif()
list(GET rows 1 first)
if(NOT first MATCHES "^1305031102\\.175304,1305031102\\.211214,ok,[0-9]+,")
  message(FATAL_ERROR "bad first row: ${first}")
endif()
file(STRINGS ${OUT}/trajectory.txt poses REGEX "^[0-9]")
list(LENGTH poses n_poses)
if(NOT n_poses EQUAL 40)
  message(FATAL_ERROR "trajectory has ${n_poses} poses, expected 40")
endif()
if(NOT stdout MATCHES "39 pairs, 39 ok, 0 failed" OR NOT stdout MATCHES "frame-to-frame RPE, translation")
  message(FATAL_ERROR "summary missing or pairs failed:\n${stdout}")
endif()
