# Runs [LAUNCH] EXE ARG and passes when it exits with EXPECT_CODE and its stderr matches the regex EXPECT.
# LAUNCH is an optional launcher with arguments separated by '|' (e.g. mpirun|-np|2).
string(REPLACE "|" ";" launch "${LAUNCH}")
execute_process(COMMAND ${launch} ${EXE} ${ARG} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 120)
if(NOT code STREQUAL "${EXPECT_CODE}")
  message(FATAL_ERROR "expected exit code ${EXPECT_CODE}, got '${code}'\nstdout:\n${out}\nstderr:\n${err}")
endif()
if(NOT err MATCHES "${EXPECT}")
  message(FATAL_ERROR "stderr does not match '${EXPECT}':\n${err}")
endif()
if(EXPECT_FILE AND NOT EXISTS "${EXPECT_FILE}")
  message(FATAL_ERROR "expected file ${EXPECT_FILE} was not written")
endif()
message(STATUS "ok: exit ${code}: ${err}")
