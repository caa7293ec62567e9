# The commit vibro is built from, for provenance (--version, HDF5 attribute git_commit):
# `git describe --always --dirty` at configure time, "unknown" outside a git checkout.
find_package(Git QUIET)
set(VIBRO_GIT_COMMIT "unknown")
if(GIT_FOUND)
  execute_process(COMMAND ${GIT_EXECUTABLE} describe --always --dirty
                  WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}
                  OUTPUT_VARIABLE _vibro_describe OUTPUT_STRIP_TRAILING_WHITESPACE
                  RESULT_VARIABLE _vibro_git_rc ERROR_QUIET)
  if(_vibro_git_rc EQUAL 0 AND _vibro_describe)
    set(VIBRO_GIT_COMMIT "${_vibro_describe}")
  endif()
endif()
