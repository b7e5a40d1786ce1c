# The evaluation the plots of bench/README.md#plots are made from, end to end on the bundled frames: the
# program writes one CSV row per evaluated pair (39) with NEES values, the summary names the
# allowance given, and bench/plot_evaluation.py turns the CSV into three PNG figures.
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
string(REPLACE "|" ";" EMULATOR "${EMULATOR}")
execute_process(
  COMMAND ${EMULATOR} ${EXE} --source ${SOURCE} --config ${CONFIG} -q --groundtruth-allowance 0.0003,0.0015
          --evaluation ${OUT}/evaluation.csv
  RESULT_VARIABLE rc OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbd-odometry exited ${rc}: ${stderr}")
endif()
if(NOT stdout MATCHES "0.30 mm, 0.086 deg per axis; given" OR NOT stdout MATCHES "joint 6-D NEES per pair \\(39\\)")
  message(FATAL_ERROR "summary without the allowance or the pair NEES:\n${stdout}")
endif()
file(STRINGS ${OUT}/evaluation.csv rows REGEX "^1305")
list(LENGTH rows n_rows)
if(NOT n_rows EQUAL 39)
  message(FATAL_ERROR "evaluation.csv has ${n_rows} pair rows, expected 39")
endif()
file(STRINGS ${OUT}/evaluation.csv allowance REGEX "^# ground-truth allowance: 0.0003 m, 0.0015 rad")
if(NOT allowance)
  message(FATAL_ERROR "evaluation.csv does not state the allowance")
endif()
execute_process(COMMAND ${PLOT} ${OUT}/evaluation.csv ${OUT}/fr1 "bundled fr1_xyz"
                RESULT_VARIABLE rc ERROR_VARIABLE stderr)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "plot_evaluation.py exited ${rc}: ${stderr}")
endif()
foreach(figure errors nees trajectory)
  file(READ ${OUT}/fr1_${figure}.png magic LIMIT 8 HEX)
  file(SIZE ${OUT}/fr1_${figure}.png size)
  if(NOT magic STREQUAL "89504e470d0a1a0a" OR size LESS 10000)
    message(FATAL_ERROR "fr1_${figure}.png is not a plot (${size} bytes, starts ${magic})")
  endif()
endforeach()
