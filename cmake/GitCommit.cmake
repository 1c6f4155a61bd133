# sapmvs_git_commit(VAR): sets VAR to the short commit of HEAD when the source
# folder is the top of a git checkout, else to "unknown" (a tarball, or a copy
# inside some other repository). HEAD, the branch's ref and packed-refs become
# configure dependencies, so a new commit re-runs the configure step and the
# value does not go stale.
function(sapmvs_git_commit var)
  # The project's folder, not the caller's: called from host/, the caller's
  # folder is never the top of the checkout.
  set(dir "${PROJECT_SOURCE_DIR}")
  set(commit unknown)
  find_package(Git QUIET)
  if(GIT_FOUND)
    execute_process(COMMAND ${GIT_EXECUTABLE} rev-parse --show-toplevel --short HEAD
      WORKING_DIRECTORY ${dir}
      OUTPUT_VARIABLE out OUTPUT_STRIP_TRAILING_WHITESPACE
      RESULT_VARIABLE rc ERROR_QUIET)
    string(REPLACE "\n" ";" out "${out}")
    list(LENGTH out n)
    if(rc EQUAL 0 AND n EQUAL 2)
      list(GET out 0 top)
      get_filename_component(top "${top}" REALPATH)
      get_filename_component(src "${dir}" REALPATH)
      if(top STREQUAL src)
        list(GET out 1 commit)
        execute_process(COMMAND ${GIT_EXECUTABLE} rev-parse --symbolic-full-name HEAD
          WORKING_DIRECTORY ${dir}
          OUTPUT_VARIABLE ref OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
        execute_process(COMMAND ${GIT_EXECUTABLE} rev-parse --git-path HEAD
                                --git-path packed-refs --git-path ${ref}
          WORKING_DIRECTORY ${dir}
          OUTPUT_VARIABLE paths OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
        string(REPLACE "\n" ";" paths "${paths}")
        foreach(f ${paths})
          if(NOT IS_ABSOLUTE "${f}")
            set(f "${dir}/${f}")
          endif()
          if(EXISTS "${f}" AND NOT IS_DIRECTORY "${f}")
            set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${f}")
          endif()
        endforeach()
      endif()
    endif()
  endif()
  set(${var} "${commit}" PARENT_SCOPE)
endfunction()
