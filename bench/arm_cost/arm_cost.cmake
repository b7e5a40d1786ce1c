# The ARM cost model, end to end: replays the bundled frames twice with the armhf build under
# qemu-user with stage_cost_plugin (SHORT and LONG frames, one processing thread, stage
# markers on), then lets arm_cost_report print the per-stage cost per frame and check BUDGET.
#   cmake -DQEMU=qemu-arm -DSYSROOT=... -DPLUGIN=...so -DREPORT=arm_cost_report -DEXE=armhf/rgbd-odometry
#         -DSOURCE=tum:DIR -DCONFIG=...yaml -DOUT=DIR -DSHORT=8 -DLONG=24 [-DBUDGET=budget.txt]
#         [-DARGS="--set|features.detector=ORB"] -P arm_cost.cmake
file(MAKE_DIRECTORY ${OUT})
string(REPLACE "|" ";" ARGS "${ARGS}")
foreach(frames ${SHORT} ${LONG})
  execute_process(
    COMMAND ${QEMU} -L ${SYSROOT} -E RGBDO_COST_MARKERS=1 -plugin ${PLUGIN},out=${OUT}/stages_${frames}.txt
            ${EXE} --source ${SOURCE} --config ${CONFIG} --max-frames ${frames} -q --set runtime.processing_threads=1 ${ARGS}
    RESULT_VARIABLE rc OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "the replay of ${frames} frames under ${QEMU} exited ${rc}: ${stderr}")
  endif()
  if(NOT stdout MATCHES "${frames} processed")
    message(FATAL_ERROR "the replay of ${frames} frames did not process them all:\n${stdout}")
  endif()
endforeach()
execute_process(COMMAND ${REPORT} ${OUT}/stages_${SHORT}.txt ${SHORT} ${OUT}/stages_${LONG}.txt ${LONG} ${BUDGET}
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the ARM cost per frame is over its budget (${BUDGET}), or could not be measured")
endif()
