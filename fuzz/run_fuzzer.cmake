# Runs one libFuzzer target for SECONDS from the committed corpus CORPUS; new inputs and any crash
# go to WORK (the committed corpus is only read). -D: FUZZER, CORPUS, WORK, SECONDS, MAX_LEN.
file(MAKE_DIRECTORY "${WORK}/corpus")
execute_process(
  COMMAND "${FUZZER}" -max_total_time=${SECONDS} -max_len=${MAX_LEN} -timeout=20 -rss_limit_mb=2560
          -malloc_limit_mb=2048 -print_final_stats=1 -artifact_prefix=${WORK}/ "${WORK}/corpus" "${CORPUS}"
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(REGEX MATCH "stat::number_of_executed_units: *[0-9]+" runs "${err}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${FUZZER} failed (${rc}); reproducer in ${WORK}:\n${err}")
endif()
message(STATUS "${FUZZER}: ${runs}")
