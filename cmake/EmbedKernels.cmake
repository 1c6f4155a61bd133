# Embeds kernels/*.cl into a generated header so the binary carries its
# kernels. Each file stays a valid .cl file on disk; the header wraps it in raw
# string literals, split into chunks below the 16 KiB literal limit some
# compilers keep, so build-log line numbers still match the file.
function(sapmvs_embed_kernels)
  cmake_parse_arguments(ARG "" "OUTPUT" "SOURCES" ${ARGN})
  add_custom_command(
    OUTPUT ${ARG_OUTPUT}
    COMMAND ${CMAKE_COMMAND} -DOUTPUT=${ARG_OUTPUT} "-DSOURCES=${ARG_SOURCES}"
            -P ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/EmbedKernelsScript.cmake
    DEPENDS ${ARG_SOURCES} ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/EmbedKernelsScript.cmake
    COMMENT "Embedding OpenCL kernels"
    VERBATIM)
endfunction()
