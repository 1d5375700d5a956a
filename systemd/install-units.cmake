# Runs inside `cmake --install` (systemd/CMakeLists.txt): CMAKE_INSTALL_PREFIX is the prefix being
# installed to, so the units name the files of this installation. Binaries and documents are under
# the prefix, where install() puts them; the configuration folder follows GNUInstallDirs' rule
# (cmake/SelfcalConfigDir.cmake: prefix /usr gives /etc/selfcal), as the programs' defaults do.
include("${SELFCAL_SOURCE_DIR}/cmake/SelfcalConfigDir.cmake")
foreach(kind BINDIR SBINDIR DOCDIR)
  set(dir "${SELFCAL_INSTALL_${kind}}")
  if(NOT IS_ABSOLUTE "${dir}")
    set(dir "${CMAKE_INSTALL_PREFIX}/${dir}")
  endif()
  set(SELFCAL_${kind} "${dir}")
endforeach()
selfcal_config_dir(SELFCAL_CONFIG_DIR "${CMAKE_INSTALL_PREFIX}" "${SELFCAL_INSTALL_SYSCONFDIR}")

# This part's entries of config/ (SELFCAL_CONFIG_ENTRIES, relative to config/) into that folder.
# The programs were built to look in SELFCAL_BUILT_CONFIG_DIR: say so when this installation's
# folder is another (an install prefix other than the configured one).
foreach(entry IN LISTS SELFCAL_CONFIG_ENTRIES)
  set(source "${SELFCAL_SOURCE_DIR}/config/${entry}")
  get_filename_component(parent "${SELFCAL_CONFIG_DIR}/${entry}" DIRECTORY)
  if(IS_DIRECTORY "${source}")
    file(INSTALL DESTINATION "${parent}" TYPE DIRECTORY FILES "${source}")
  elseif(EXISTS "${source}")
    file(INSTALL DESTINATION "${parent}" TYPE FILE FILES "${source}")
  else()
    message(FATAL_ERROR "systemd/CMakeLists.txt installs config/${entry}, which does not exist")
  endif()
endforeach()
if(SELFCAL_CONFIG_ENTRIES AND NOT SELFCAL_CONFIG_DIR STREQUAL SELFCAL_BUILT_CONFIG_DIR)
  message(STATUS "Note: the configuration is in ${SELFCAL_CONFIG_DIR}; the programs default to "
                 "${SELFCAL_BUILT_CONFIG_DIR} (configure with -DCMAKE_INSTALL_PREFIX="
                 "${CMAKE_INSTALL_PREFIX} for defaults that match, or pass their --config)")
endif()

set(unit_dir "${SELFCAL_SYSTEMD_UNIT_DIR}")
if(NOT IS_ABSOLUTE "${unit_dir}")
  set(unit_dir "${CMAKE_INSTALL_PREFIX}/${unit_dir}")
endif()
foreach(template IN LISTS SELFCAL_UNIT_TEMPLATES)
  get_filename_component(unit "${template}" NAME_WLE)
  set(destination "$ENV{DESTDIR}${unit_dir}/${unit}")
  message(STATUS "Installing: ${destination}")
  configure_file("${template}" "${destination}" @ONLY)
  list(APPEND CMAKE_INSTALL_MANIFEST_FILES "${unit_dir}/${unit}")
endforeach()
