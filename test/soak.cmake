# Soak: the virtual sensor plays the bundled recording LOOPS times at RATE times its recorded
# rate (40 x LOOPS frames), the whole program reads it live. Asserted, independent of the machine's
# speed or load: every frame delivered is processed or counted (skipped / dropped), resident
# memory does not grow after warm-up by more than MAX_GROWTH_MB, no descriptor or thread is
# leaked, the same frame pairs give the same motions pass after pass (nothing drifts), and
# (in a sanitised build) nothing leaks or errs.
# The 100,000-frame version of the long run (bench/MEASUREMENTS.md#long-runs-soak) is the
# same command with loop=2500 (at rate=3, as fast as the program keeps up natively: 19 min).
string(REPLACE "|" ";" EMULATOR "${EMULATOR}")
file(REMOVE ${LOG} ${LOG}.1)
execute_process(
  COMMAND ${EMULATOR} ${EXE} "--source" "openni://rgbdo-virtual:${DATA}?rate=${RATE}&loop=${LOOPS}" --config ${CONFIG} -q
          --set sensor.reconnect_timeout_s=0 --log ${LOG}
  RESULT_VARIABLE rc OUTPUT_VARIABLE stdout ERROR_VARIABLE stderr)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "rgbd-odometry exited ${rc}:\n${stdout}\n${stderr}")
endif()
math(EXPR delivered "40 * ${LOOPS}")
if(NOT stdout MATCHES "frames: ([0-9]+) processed, ([0-9]+) skipped \\(processing behind\\), ([0-9]+) without a depth frame within 20 ms, ([0-9]+) dropped by the sensor")
  message(FATAL_ERROR "no frame accounting in the summary:\n${stdout}")
endif()
set(processed ${CMAKE_MATCH_1})
math(EXPR accounted "${CMAKE_MATCH_1} + ${CMAKE_MATCH_2} + ${CMAKE_MATCH_3} + ${CMAKE_MATCH_4}")
math(EXPR not_processed "${CMAKE_MATCH_2} + ${CMAKE_MATCH_3} + ${CMAKE_MATCH_4}")
if(NOT accounted EQUAL delivered)
  message(FATAL_ERROR "${delivered} frames delivered, ${accounted} accounted for:\n${stdout}")
endif()

# Repeated input, repeated results: after the first 200 pairs (the online stamp-jitter window
# filled with the recording's intervals) a pass's 40 pairs give the motions (status, inliers,
# translation, rotation) of the passes before, to the last printed digit. A disturbance starts
# a run of new motions that ends once the state is back on its looped course (a whole pass of
# motions seen before): a frame skipped or dropped (a pair across the gap, then, through the
# motion window's prior and the sensor constants learnt from the data, the pairs after it:
# measured 52-136 new rows a frame, up to 207 with several frames in one run), or the loop's
# own jump (frame 40 back to frame 1: 0.41 m in 67 ms), which is a pair like no other and comes
# out one of two ways from pass to pass (78 inliers and a wrong 0.2 m, or 103 and the right
# motion; measured: its other way once in 250 passes, with 140 new rows after it, no frame
# lost). Asserted: every run ends within 250 pairs a disturbance it can hold, and there are no
# more runs than disturbances can make (the first pass, the jump's two ways, the frames not
# processed). State that drifts, or creeps by a pair a pass, makes one run that never ends.
file(STRINGS ${LOG} rows)
# A motion seen before is a variable set (a hash lookup: a list search made the check take
# as long as the run).
set(distinct 0)
set(index 0)
set(compared 0)
set(runs 0)
set(run_start 0)
set(since_new 40)  # pairs since the last new motion: a whole pass of old ones ends a run
set(longest_run 0)
foreach(row IN LISTS rows)
  math(EXPR index "${index} + 1")
  if(index GREATER 201 AND row MATCHES "^[^,]*,[^,]*,([^,]*,[^,]*,[^,]*,[^,]*,[^,]*,[^,]*,[^,]*,[^,]*,[^,]*),")
    math(EXPR compared "${compared} + 1")
    string(MD5 motion "${CMAKE_MATCH_1}")
    if(NOT DEFINED seen_${motion})
      set(seen_${motion} 1)
      math(EXPR distinct "${distinct} + 1")
      if(since_new GREATER_EQUAL 40)
        math(EXPR runs "${runs} + 1")
        set(run_start ${index})
      endif()
      math(EXPR run_length "${index} - ${run_start} + 1")
      if(run_length GREATER longest_run)
        set(longest_run ${run_length})
      endif()
      set(since_new 0)
    else()
      math(EXPR since_new "${since_new} + 1")
    endif()
  endif()
endforeach()
math(EXPR runs_allowed "3 + ${not_processed}")
math(EXPR run_allowed "250 * (1 + ${not_processed})")
message(STATUS "${compared} pairs after the first 200: ${distinct} distinct motions (one pass: 40) in ${runs} runs of new "
               "motions, the longest ${longest_run} pairs (allowed ${runs_allowed} runs of up to ${run_allowed} with "
               "${not_processed} frames not processed)")
if(compared LESS_EQUAL run_allowed)
  message(STATUS "too few pairs for a comparison of passes (an emulator or a sanitizer skips frames): not compared")
elseif(longest_run GREATER run_allowed OR runs GREATER runs_allowed)
  message(FATAL_ERROR "repeated input gave ${distinct} distinct motions over ${compared} pairs in ${runs} runs, the longest "
                      "${longest_run} pairs (one pass has 40 pairs)")
endif()

if(NOT stdout MATCHES "resources, memory the least over [0-9]+ frames: ")
  # Too few frames came out for a sample after warm-up (under qemu or a sanitizer the reader
  # skips frames it cannot keep up with): the accounting above is what this run can prove.
  if(delivered GREATER 1000 OR processed GREATER 800)
    message(FATAL_ERROR "no resource line in the summary:\n${stdout}")
  endif()
  message(STATUS "${delivered} frames delivered, all accounted for; too few processed for a resource comparison")
  return()
endif()
# "resources, memory the least over 200 frames: after 200 frames RSS X MB, F fds, T threads;
# [after H frames ...; ]after N frames ...": memory the least of each window's samples, so that
# a buffer in flight when one is taken (a colour frame being decoded: 0.9 MB) does not count.
string(REGEX MATCH "resources, memory the least over [0-9]+ frames: [^\n]*" resources "${stdout}")
string(REGEX MATCHALL "after [0-9]+ frames RSS [0-9.]+ MB, [0-9]+ fds, [0-9]+ threads" samples "${resources}")
list(LENGTH samples sample_count)
if(sample_count LESS 2)
  message(FATAL_ERROR "no warm-up and end samples in the summary:\n${stdout}")
endif()
foreach(which IN ITEMS warm half end)
  # A run too short for a halfway sample (the sanitizers' 400 frames): the end stands in.
  if(which STREQUAL "warm")
    list(GET samples 0 sample)
  elseif(which STREQUAL "half" AND sample_count GREATER 2)
    list(GET samples 1 sample)
  else()
    list(GET samples -1 sample)
  endif()
  string(REGEX MATCH "after ([0-9]+) frames RSS ([0-9.]+) MB, ([0-9]+) fds, ([0-9]+) threads" _ "${sample}")
  set(frames_${which} ${CMAKE_MATCH_1})
  set(rss_${which} ${CMAKE_MATCH_2})
  set(fds_${which} ${CMAKE_MATCH_3})
  set(threads_${which} ${CMAKE_MATCH_4})
  string(REPLACE "." "" rss_${which}_tenths ${CMAKE_MATCH_2})  # CMake has no floating point: tenths of a MB
endforeach()
message(STATUS "${delivered} frames: RSS ${rss_warm} MB after ${frames_warm}, ${rss_half} MB after ${frames_half}, ${rss_end} MB after ${frames_end}; fds ${fds_warm} -> ${fds_end}; threads ${threads_warm} -> ${threads_end}")
math(EXPR late "${delivered} / 2")
if(frames_end LESS late)
  message(FATAL_ERROR "the last resource sample is from frame ${frames_end} of ${delivered}")
endif()
# A descriptor may be open for a moment when a sample is taken (the sensor reading its next
# image file): two of slack; a leak of one per frame would be thousands.
math(EXPR fds_allowed "${fds_warm} + 2")
if(fds_end GREATER fds_allowed OR NOT threads_end EQUAL threads_warm)
  message(FATAL_ERROR "descriptors ${fds_warm} -> ${fds_end}, threads ${threads_warm} -> ${threads_end}")
endif()
# Memory settles in steps over the first thousands of frames (measured, sampling /proc every
# 3 s with a CPU hog on each core: +2.4 MB by frame 500, +0.9 MB near frame 2,000, flat to
# 5,000; 100,000 frames: +2.6 MB in all), so two bounds: after warm-up, MAX_GROWTH_MB in all;
# from the halfway window (a quarter to half of the run) to the end, MAX_LATE_GROWTH_MB, which
# a leak of 850 bytes a frame exceeds over the native run's 4,800 frames. Even as the least of each window's
# samples, memory wanders by up to 0.8 MB from window to window under load (measured: four runs
# of 10,000 frames, a CPU hog on each core: late growth 0.0-0.8 MB), so this is a backstop for
# leaks and growing containers; that the pipeline allocates nothing per frame at all after
# warm-up is test_allocations' exact count.
math(EXPR growth "${rss_end_tenths} - ${rss_warm_tenths}")
math(EXPR late_growth "${rss_end_tenths} - ${rss_half_tenths}")
math(EXPR allowed "${MAX_GROWTH_MB} * 10")
math(EXPR late_allowed "${MAX_LATE_GROWTH_MB} * 10")
if(growth GREATER allowed)
  message(FATAL_ERROR "resident memory grew by ${growth}/10 MB after warm-up (allowed ${MAX_GROWTH_MB} MB)")
endif()
if(late_growth GREATER late_allowed)
  message(FATAL_ERROR "resident memory grew by ${late_growth}/10 MB from frame ${frames_half} to ${frames_end} (allowed ${MAX_LATE_GROWTH_MB} MB)")
endif()
