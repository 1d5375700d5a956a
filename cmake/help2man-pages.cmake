# Script (cmake -P) behind selfcal_man_page (cmake/SelfcalManPages.cmake): the manual page of
# PROGRAM, and with SUBCOMMANDS one per subcommand its --help lists, made by help2man from --help
# and gzipped into OUT_DIR/manSECTION/NAME[-SUBCOMMAND].SECTION.gz.
# Variables: HELP2MAN, GZIP, PROGRAM, NAME, SECTION, VERSION, SUBCOMMANDS (ON/OFF),
# SEE_ALSO (comma-separated "page(n)"), GUIDE (an installed document, or empty), OUT_DIR.
set(ENV{LC_ALL} C.UTF-8)
set(man_dir "${OUT_DIR}/man${SECTION}")
file(REMOVE_RECURSE "${man_dir}")
file(MAKE_DIRECTORY "${man_dir}")

# The --help text of `command` (a list), or a fatal error.
function(help_of out_var)
  execute_process(COMMAND ${ARGN} --help OUTPUT_VARIABLE text RESULT_VARIABLE status)
  if(NOT status EQUAL 0 OR text STREQUAL "")
    message(FATAL_ERROR "${ARGN} --help failed (${status})")
  endif()
  set(${out_var} "${text}" PARENT_SCOPE)
endfunction()

# Writes page `page` of `command` (the program, or a wrapper running one subcommand); `see_also`
# is a list of "page(n)".
function(make_page page command see_also)
  help_of(help ${command})
  # NAME's summary: the first line of --help without the leading "program: ", to the first ". ".
  string(REGEX MATCH "^[^\n]*" summary "${help}")
  string(REGEX REPLACE "^[a-z0-9 -]+: " "" summary "${summary}")
  string(REGEX REPLACE "\\. .*$" "" summary "${summary}")
  string(REGEX REPLACE "\\.$" "" summary "${summary}")
  set(include "[SEE ALSO]\n")
  set(separator "")
  foreach(entry IN LISTS see_also)
    string(REGEX REPLACE "^(.*)\\((.*)\\)$" ".BR \\1 (\\2)" entry "${entry}")
    string(APPEND include "${separator}${entry}")
    set(separator ",\n")
  endforeach()
  string(APPEND include "\n")
  if(GUIDE)
    string(APPEND include ".PP\nThe guide: \\fI${GUIDE}\\fR\n")
  endif()
  file(WRITE "${OUT_DIR}/${page}.h2m" "${include}")
  set(out "${man_dir}/${page}.${SECTION}")
  execute_process(
    COMMAND "${HELP2MAN}" --no-info --section=${SECTION} --version-string=${VERSION}
            "--name=${summary}" "--include=${OUT_DIR}/${page}.h2m" "--output=${out}" ${command}
    RESULT_VARIABLE status)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "help2man ${command} failed (${status})")
  endif()
  execute_process(COMMAND "${GZIP}" -9nf "${out}" RESULT_VARIABLE status)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "gzip ${out} failed (${status})")
  endif()
endfunction()

string(REPLACE "," ";" see_also "${SEE_ALSO}")
if(NOT SUBCOMMANDS)
  make_page("${NAME}" "${PROGRAM}" "${see_also}")
  return()
endif()

# The subcommands: the lines "  name  description" after "Subcommands:" in --help.
help_of(help "${PROGRAM}")
string(REGEX MATCH "\nSubcommands:\n.*$" listed "${help}")
string(REGEX MATCHALL "\n  [a-z][a-z0-9-]*" names "${listed}")
set(pages "")
foreach(name IN LISTS names)
  string(STRIP "${name}" name)
  # help2man names the page after the program it runs: a wrapper named NAME-SUBCOMMAND.
  set(wrapper "${OUT_DIR}/bin/${NAME}-${name}")
  file(WRITE "${wrapper}" "#!/bin/sh\nexec '${PROGRAM}' ${name} \"$@\"\n")
  file(CHMOD "${wrapper}" PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE)
  make_page("${NAME}-${name}" "${wrapper}" "${NAME}(${SECTION})")
  list(APPEND pages "${NAME}-${name}(${SECTION})")
endforeach()
make_page("${NAME}" "${PROGRAM}" "${pages};${see_also}")
