# MODE=replay: run FUZZER once over every file in INPUTS (a missing directory: nothing to do).
# MODE=fuzz: copy INPUTS to WORK and fuzz from it for RUNS inputs with seed 1 (one process:
# a bounded run on every machine, and a finding names its input; what it explores still varies
# a little from run to run, as libFuzzer is not fully deterministic). The environment's
# RGBDO_FUZZ_SEED picks another seed: `deploy/setup.sh fuzz-sweep` runs a range of them.
if(MODE STREQUAL "replay")
  file(GLOB inputs ${INPUTS}/*)
  if(NOT inputs)
    message(STATUS "no regression inputs in ${INPUTS}")
    return()
  endif()
  execute_process(COMMAND ${FUZZER} ${inputs} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
else()
  set(seed 1)
  if(DEFINED ENV{RGBDO_FUZZ_SEED})
    if(NOT "$ENV{RGBDO_FUZZ_SEED}" MATCHES "^[0-9]+$")
      message(FATAL_ERROR "RGBDO_FUZZ_SEED must be a whole number, not '$ENV{RGBDO_FUZZ_SEED}'")
    endif()
    set(seed $ENV{RGBDO_FUZZ_SEED})
  endif()
  set(seed_note " (seed ${seed})")
  file(REMOVE_RECURSE ${WORK})
  file(MAKE_DIRECTORY ${WORK}/corpus ${WORK}/artifacts)
  file(GLOB seeds ${INPUTS}/*)
  if(NOT seeds)
    message(FATAL_ERROR "no seed corpus in ${INPUTS}")
  endif()
  file(COPY ${seeds} DESTINATION ${WORK}/corpus)
  execute_process(
    COMMAND ${FUZZER} ${WORK}/corpus -runs=${RUNS} -seed=${seed} -timeout=60 -rss_limit_mb=2048
            -artifact_prefix=${WORK}/artifacts/ -print_final_stats=1
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
endif()
string(REGEX MATCH "stat::number_of_executed_units: *[0-9]+" runs "${err}")
message(STATUS "${FUZZER}: ${runs}${seed_note}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${FUZZER}${seed_note} failed (${rc}):\n${err}")
endif()
