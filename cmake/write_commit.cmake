# Run at every build (src/CMakeLists.txt, target caustica_commit): writes OUT with the commit
# of the source tree SRC, and rewrites it only when the commit changed, so that only
# experiment/build_info.cpp recompiles, and only then.
execute_process(COMMAND git describe --always --dirty --abbrev=12
                WORKING_DIRECTORY ${SRC}
                OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE
                ERROR_QUIET)
if(NOT commit)
  set(commit unknown)
endif()
set(content "#define CAUSTICA_GIT_COMMIT \"${commit}\"\n")
set(old "")
if(EXISTS ${OUT})
  file(READ ${OUT} old)
endif()
if(NOT old STREQUAL content)
  file(WRITE ${OUT} "${content}")
endif()
