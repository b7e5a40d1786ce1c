# A run killed mid-way, then restarted with the same --log (what the packaged service does
# after a failure): the killed run's log survives, untouched, as FILE.1, and holds whole rows
# only (each row is flushed as written); the restarted run writes FILE afresh.
#   cmake [-DEMULATOR=qemu|-L|...] -DEXE=... -DSOURCE=tum:DIR -DCONFIG=... -DOUT=DIR -P log_restart.cmake
file(REMOVE_RECURSE ${OUT})
file(MAKE_DIRECTORY ${OUT})
string(REPLACE "|" " " EMULATOR "${EMULATOR}")
set(log ${OUT}/odometry.csv)
# SIGKILL once the log holds 5 lines, whatever the machine's speed: no handler runs, nothing
# is flushed at exit. (A run that ends first leaves a complete log: the checks still hold.)
execute_process(COMMAND sh -c "${EMULATOR} ${EXE} --source ${SOURCE} --config ${CONFIG} --log ${log} -q >/dev/null 2>&1 & pid=$!
  while kill -0 $pid 2>/dev/null && ! { [ -f ${log} ] && [ $(wc -l < ${log}) -ge 5 ]; }; do sleep 0.02; done
  kill -9 $pid 2>/dev/null; wait $pid; echo $?"
  OUTPUT_VARIABLE killed_rc OUTPUT_STRIP_TRAILING_WHITESPACE)
if(NOT EXISTS ${log})
  message(FATAL_ERROR "the killed run left no log (exit ${killed_rc})")
endif()
file(READ ${log} killed)
string(LENGTH "${killed}" killed_length)
string(REGEX MATCHALL "\n" newlines "${killed}")
list(LENGTH newlines killed_rows)
if(killed_length EQUAL 0 OR NOT killed MATCHES "\n$")
  message(FATAL_ERROR "the killed run's log ends inside a row (${killed_length} bytes)")
endif()
separate_arguments(emulator_args UNIX_COMMAND "${EMULATOR}")
execute_process(COMMAND ${emulator_args} ${EXE} --source ${SOURCE} --config ${CONFIG} --log ${log} -q RESULT_VARIABLE rc
                OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the restarted run exited ${rc}: ${err}")
endif()
file(READ ${log}.1 kept)
if(NOT kept STREQUAL killed)
  message(FATAL_ERROR "the killed run's log was not kept as it was (${killed_rows} lines before the restart)")
endif()
file(STRINGS ${log} rows)
list(LENGTH rows n)
if(NOT n EQUAL 40)
  message(FATAL_ERROR "the restarted run's log has ${n} lines, not 40")
endif()
message(STATUS "killed run (exit ${killed_rc}): ${killed_rows} lines kept as odometry.csv.1; restarted run: ${n} lines")
