# Manual pages, made at build time by help2man from each program's own --help (docs/packaging.md),
# so a page cannot drift from the options the program parses. One page per installed program,
# one more per subcommand of `selfcal` (selfcal-calibrate(1), ...); section 1 for programs in
# bin/, 8 for the daemon in sbin/ (Debian's convention for system services). The pages are
# installed gzipped (-9n, as Debian wants them) in the install part of their program.
# A cross build makes none (its programs do not run on the build machine).
if(CMAKE_CROSSCOMPILING)
  set(_selfcal_man_default OFF)
else()
  set(_selfcal_man_default ON)
endif()
option(SELFCAL_MAN_PAGES "Make and install the manual pages (needs help2man)" ${_selfcal_man_default})
if(SELFCAL_MAN_PAGES)
  find_program(HELP2MAN help2man)
  if(NOT HELP2MAN)
    message(FATAL_ERROR "help2man not found (tools/setup-deps installs it); or configure with "
                        "-DSELFCAL_MAN_PAGES=OFF")
  endif()
  find_program(GZIP gzip REQUIRED)
endif()

# selfcal_man_page(TARGET target COMPONENT part [SECTION 1|8] [SUBCOMMANDS] [GUIDE file.md]
#                  [SEE_ALSO page(n)...])
# Makes TARGET's page (and with SUBCOMMANDS one page per subcommand its --help lists) into
# build/man/TARGET/manSECTION/ and installs them into MANDIR/manSECTION with COMPONENT. The NAME
# line is the first line of --help; SEE ALSO names the pages given and GUIDE, one of the documents
# installed in DOCDIR (systemd/CMakeLists.txt).
function(selfcal_man_page)
  if(NOT SELFCAL_MAN_PAGES)
    return()
  endif()
  cmake_parse_arguments(PAGE "SUBCOMMANDS" "TARGET;COMPONENT;SECTION;GUIDE" "SEE_ALSO" ${ARGN})
  if(NOT PAGE_SECTION)
    set(PAGE_SECTION 1)
  endif()
  set(dir "${PROJECT_BINARY_DIR}/man/${PAGE_TARGET}")
  set(page "${dir}/man${PAGE_SECTION}/${PAGE_TARGET}.${PAGE_SECTION}.gz")
  string(REPLACE ";" "," see_also "${PAGE_SEE_ALSO}")
  set(guide "")
  if(PAGE_GUIDE)
    set(guide "${CMAKE_INSTALL_FULL_DOCDIR}/${PAGE_GUIDE}")
  endif()
  add_custom_command(
    OUTPUT "${page}"
    COMMAND "${CMAKE_COMMAND}" -DHELP2MAN=${HELP2MAN} -DGZIP=${GZIP}
            -DPROGRAM=$<TARGET_FILE:${PAGE_TARGET}> -DNAME=${PAGE_TARGET}
            -DSECTION=${PAGE_SECTION} -DVERSION=${PROJECT_VERSION} -DSUBCOMMANDS=${PAGE_SUBCOMMANDS}
            "-DSEE_ALSO=${see_also}" "-DGUIDE=${guide}" -DOUT_DIR=${dir}
            -P "${PROJECT_SOURCE_DIR}/cmake/help2man-pages.cmake"
    DEPENDS ${PAGE_TARGET} "${PROJECT_SOURCE_DIR}/cmake/help2man-pages.cmake"
    COMMENT "Manual page of ${PAGE_TARGET}" VERBATIM)
  add_custom_target(${PAGE_TARGET}_man ALL DEPENDS "${page}")
  install(DIRECTORY "${dir}/man${PAGE_SECTION}" DESTINATION "${CMAKE_INSTALL_MANDIR}"
          COMPONENT ${PAGE_COMPONENT}
          FILES_MATCHING PATTERN "*.gz")
endfunction()
