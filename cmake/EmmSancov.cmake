# emm_sancov_executable(TARGET name SOURCES src... [OUTPUT_NAME name]
#                       [INCLUDE_DIRECTORIES dir...] [COMPILE_DEFINITIONS def...]
#                       [COMPILE_OPTIONS opt...] [LINK_LIBRARIES lib...])
#
# Builds a program for EMM_CAPTURE=sancov (docs/design.md "The shim"): its
# sources are compiled by clang with sanitizer-coverage callbacks on every
# load, store and edge, and vectorisation off (wider-than-16-byte vector
# accesses are not reported). The flags go on the compile step only. The
# program links the hooks library emm::hooks (libemmhooks.so: no-op
# callbacks), so it runs with or without emm; under `emm run` the preloaded
# shim's callbacks win.
#
# The same file serves emm's own build and, installed, any project that says
# find_package(emm): there emm::hooks is the installed library.
#
# clang 14's `edge` alone emits no callback: trace-pc-guard is edge coverage
# with one, which the shim counts as work between accesses.
#
# -mllvm -disable-machine-sink: the callbacks are placed on the IR's loads,
# and the back end's machine sinking would then move a load below its
# callback into a branch that does not always run, so the capture would
# record a load the binary does not make (on examples/flood_walk.c, 4.5% of
# the records: the same binary gave 4.5% fewer under the valgrind capture).
# Without it, the sancov capture records exactly the loads the binary makes.
#
# When the project's C compiler is not clang, the sources are compiled by a
# clang found on the PATH, with the include directories of the LINK_LIBRARIES
# targets (emm::emm's headers, say) and those given here; without clang the
# target is skipped with a message.

# emm_sancov_flags(VAR): the compile flags, for a build that is not CMake's
# (emm-sancov.pc has the same).
function(emm_sancov_flags var)
  set(${var} -fsanitize-coverage=trace-pc-guard,trace-loads,trace-stores
      -fno-vectorize -fno-slp-vectorize -mllvm -disable-machine-sink PARENT_SCOPE)
endfunction()

function(emm_sancov_executable)
  emm_sancov_flags(EMM_SANCOV_FLAGS)
  cmake_parse_arguments(S "" "TARGET;OUTPUT_NAME"
    "SOURCES;INCLUDE_DIRECTORIES;COMPILE_DEFINITIONS;COMPILE_OPTIONS;LINK_LIBRARIES" ${ARGN})
  if(NOT S_TARGET OR NOT S_SOURCES)
    message(FATAL_ERROR "emm_sancov_executable: TARGET and SOURCES are required")
  endif()
  if(NOT TARGET emm::hooks)
    message(STATUS "emm: ${S_TARGET} not built (no emm::hooks: emm's sanitizer build leaves "
                   "the hooks out; elsewhere find_package(emm) first)")
    return()
  endif()
  if(CMAKE_C_COMPILER_ID MATCHES "Clang")
    add_executable(${S_TARGET} ${S_SOURCES})
    # CMake de-duplicates options: -mllvm stays with its argument as one.
    string(REPLACE "-mllvm;" "SHELL:-mllvm " flags "${EMM_SANCOV_FLAGS}")
    target_compile_options(${S_TARGET} PRIVATE ${flags} ${S_COMPILE_OPTIONS})
    target_include_directories(${S_TARGET} PRIVATE ${S_INCLUDE_DIRECTORIES})
    target_compile_definitions(${S_TARGET} PRIVATE ${S_COMPILE_DEFINITIONS})
  else()
    find_program(EMM_CLANG NAMES clang clang-19 clang-18 clang-17 clang-16 clang-15 clang-14)
    if(NOT EMM_CLANG)
      message(STATUS "emm: no clang found: ${S_TARGET} (EMM_CAPTURE=sancov build) not built")
      return()
    endif()
    set(flags -std=c11 -O2 -g -fPIE)
    foreach(d ${S_INCLUDE_DIRECTORIES})
      list(APPEND flags -I${d})
    endforeach()
    # The headers of the targets linked, as CMake would give a compiler it runs.
    foreach(lib ${S_LINK_LIBRARIES})
      if(TARGET ${lib})
        set(inc "$<TARGET_PROPERTY:${lib},INTERFACE_INCLUDE_DIRECTORIES>")
        list(APPEND flags "$<$<BOOL:${inc}>:-I$<JOIN:${inc},$<SEMICOLON>-I>>")
      endif()
    endforeach()
    foreach(d ${S_COMPILE_DEFINITIONS})
      list(APPEND flags -D${d})
    endforeach()
    set(objects)
    file(MAKE_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR}/${S_TARGET}.sancov)
    foreach(src ${S_SOURCES})
      get_filename_component(abs ${src} ABSOLUTE)
      get_filename_component(stem ${src} NAME_WE)
      set(obj ${CMAKE_CURRENT_BINARY_DIR}/${S_TARGET}.sancov/${stem}.o)
      add_custom_command(OUTPUT ${obj}
        COMMAND ${EMM_CLANG} ${flags} ${EMM_SANCOV_FLAGS} ${S_COMPILE_OPTIONS}
                -MD -MF ${obj}.d -c ${abs} -o ${obj}
        DEPENDS ${abs} DEPFILE ${obj}.d
        COMMENT "Compiling ${src} with sanitizer coverage (${S_TARGET})"
        VERBATIM COMMAND_EXPAND_LISTS)
      list(APPEND objects ${obj})
    endforeach()
    add_executable(${S_TARGET} ${objects})
    set_target_properties(${S_TARGET} PROPERTIES LINKER_LANGUAGE C)
  endif()
  target_link_libraries(${S_TARGET} PRIVATE emm::hooks ${S_LINK_LIBRARIES})
  if(S_OUTPUT_NAME)
    set_target_properties(${S_TARGET} PROPERTIES OUTPUT_NAME ${S_OUTPUT_NAME})
  endif()
endfunction()
