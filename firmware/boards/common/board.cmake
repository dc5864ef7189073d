# Helpers of the board folders (included by each board's CMakeLists.txt).
#   board_common_library(<name> <core library>): startup and semihosting for that CPU
#   board_firmware(<name> LINKER_SCRIPT <ld> SOURCES <c...> LIBRARIES <libs...>): an .elf
#     image linked with --gc-sections and newlib-nano, with a map file; its flash and RAM
#     use are printed after the link.
include_guard(GLOBAL)

function(board_common_library name core_library)
  set(BOARD_COMMON_DIR ${CMAKE_CURRENT_FUNCTION_LIST_DIR})
  if(TARGET ${name})
    return()
  endif()
  add_library(${name} STATIC ${BOARD_COMMON_DIR}/startup.c ${BOARD_COMMON_DIR}/semihosting.c
              ${BOARD_COMMON_DIR}/board_text.c)
  target_include_directories(${name} PUBLIC ${BOARD_COMMON_DIR})
  target_compile_options(${name} PRIVATE ${NODE_C_OPTIONS} -Wpedantic -Wshadow -Wdouble-promotion)
  target_link_libraries(${name} PUBLIC ${core_library})
endfunction()

function(board_firmware name)
  set(BOARD_COMMON_DIR ${CMAKE_CURRENT_FUNCTION_LIST_DIR})
  cmake_parse_arguments(ARG "" "LINKER_SCRIPT" "SOURCES;LIBRARIES" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  set_target_properties(${name} PROPERTIES SUFFIX .elf
    LINK_DEPENDS "${ARG_LINKER_SCRIPT};${BOARD_COMMON_DIR}/sections.ld")
  target_compile_options(${name} PRIVATE ${NODE_C_OPTIONS} -Wpedantic -Wshadow -Wdouble-promotion)
  target_link_libraries(${name} PRIVATE ${ARG_LIBRARIES} m)
  target_link_options(${name} PRIVATE
    -nostartfiles --specs=nano.specs --specs=nosys.specs -Wl,--undefined=board_reset_handler
    -Wl,--gc-sections -Wl,-T,${ARG_LINKER_SCRIPT} -L${BOARD_COMMON_DIR}
    -Wl,-Map=$<TARGET_FILE_DIR:${name}>/${name}.map)
  add_custom_command(TARGET ${name} POST_BUILD COMMAND ${CMAKE_SIZE} $<TARGET_FILE:${name}> VERBATIM)
endfunction()
