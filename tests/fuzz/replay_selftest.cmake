# The replay driver's own test (CTest fuzz_replay.driver_selftest):
#   cmake -DDRIVER=<replay_selftest> -DDIR=<scratch folder> -P replay_selftest.cmake
# A clean seed passes; a trapping seed, an escaping exception and a crash only
# a mutant reaches each fail the run, name the input and leave its bytes in
# fuzz-finding-replay_selftest.
file(REMOVE_RECURSE ${DIR})
file(MAKE_DIRECTORY ${DIR})
set(finding ${DIR}/fuzz-finding-replay_selftest)

function(replay expect_ok args expect_text expect_bytes)
  file(REMOVE ${finding})
  execute_process(COMMAND ${DRIVER} ${args} WORKING_DIRECTORY ${DIR} RESULT_VARIABLE rv OUTPUT_VARIABLE out
                  ERROR_VARIABLE err)
  if(expect_ok AND NOT rv EQUAL 0)
    message(FATAL_ERROR "replay ${args}: failed (${rv}) on a clean input:\n${out}${err}")
  elseif(NOT expect_ok)
    if(rv EQUAL 0)
      message(FATAL_ERROR "replay ${args}: exit 0, a finding was expected:\n${out}${err}")
    endif()
    string(FIND "${err}" "${expect_text}" at)
    if(at EQUAL -1)
      message(FATAL_ERROR "replay ${args}: no '${expect_text}' in:\n${err}")
    endif()
    if(NOT EXISTS ${finding})
      message(FATAL_ERROR "replay ${args}: the input was not saved as ${finding}")
    endif()
    file(READ ${finding} saved)
    if(NOT "${expect_bytes}" STREQUAL "" AND NOT saved STREQUAL expect_bytes)
      message(FATAL_ERROR "replay ${args}: saved '${saved}', not '${expect_bytes}'")
    endif()
  endif()
endfunction()

file(WRITE ${DIR}/clean "ABCDEFGHIJ")
file(WRITE ${DIR}/trap "TRAP and more")
file(WRITE ${DIR}/throw "THROW it")
replay(TRUE "--runs;0;${DIR}/clean" "" "")
replay(FALSE "--runs;0;${DIR}/clean;${DIR}/trap" "on seed trap (13 bytes)" "TRAP and more")
replay(FALSE "--runs;0;${DIR}/throw" "exception escaped: planted on seed throw" "THROW it")
replay(FALSE "--runs;2000;${DIR}/clean" "of seed clean (--seed 1)" "")
