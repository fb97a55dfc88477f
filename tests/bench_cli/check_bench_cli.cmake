# Runs one benchmark program with bad command lines only (it must exit at once: nothing here
# starts a benchmark) and checks the answers: --help prints the usage, exit 0; an unknown flag,
# a flag without its value and a malformed value are refused with exit 2 and a message naming
# the argument.
#   cmake -DBENCH=path -DNAME=bench_x [-DMISSING=--flag] -DBAD_VALUE=x [-DBAD_OPT=--flag]
#         -DBAD_REGEX=regex -P check_bench_cli.cmake
set(failures "")

# run(<expected code> <stream regex> <out|err> args...)
function(run code regex stream)
  execute_process(COMMAND ${BENCH} ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                  TIMEOUT 30)
  set(text "${${stream}}")
  if(NOT rc STREQUAL "${code}" OR NOT text MATCHES "${regex}")
    string(APPEND failures "\n  ${NAME} ${ARGN}: exit ${rc} (expected ${code}), std${stream} "
                          "'${text}' (expected to match '${regex}')")
    set(failures "${failures}" PARENT_SCOPE)
  endif()
endfunction()

run(0 "Usage: ${NAME}" out --help)
run(2 "^${NAME}: [^\n]*--no-such-flag" err --no-such-flag)
if(MISSING)
  run(2 "${MISSING}" err ${MISSING})
endif()
if(BAD_OPT)
  run(2 "${BAD_REGEX}" err ${BAD_OPT} ${BAD_VALUE})
else()
  run(2 "${BAD_REGEX}" err ${BAD_VALUE})
endif()
if(failures)
  message(FATAL_ERROR "bad command lines not answered as they should be:${failures}")
endif()
message(STATUS "${NAME}: --help, an unknown flag, a missing and a malformed value answered")
