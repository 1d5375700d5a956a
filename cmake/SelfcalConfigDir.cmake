# Where config/ is installed (SYSCONFDIR/selfcal), in one place for the programs' compiled-in
# defaults (at configure time) and for the installed files and units (at `cmake --install` time,
# for the prefix being installed to). GNUInstallDirs' rule for a relative SYSCONFDIR: prefix /usr
# or / gives /etc, /opt/NAME gives /etc/opt/NAME, any other prefix P gives P/etc; selfcal/ goes
# below. An absolute CMAKE_INSTALL_SYSCONFDIR is taken as it is.
if(NOT COMMAND GNUInstallDirs_get_absolute_install_dir)
  # In an install script: no language is enabled, so name LIBDIR to keep GNUInstallDirs quiet.
  function(_selfcal_load_gnuinstalldirs)
    set(CMAKE_INSTALL_LIBDIR lib)
    include(GNUInstallDirs)
  endfunction()
  _selfcal_load_gnuinstalldirs()
endif()

# Sets `out_var` to the configuration folder for install prefix `prefix` and SYSCONFDIR `sysconfdir`.
function(selfcal_config_dir out_var prefix sysconfdir)
  set(CMAKE_INSTALL_PREFIX "${prefix}")
  set(dir "${sysconfdir}")
  GNUInstallDirs_get_absolute_install_dir(absolute dir SYSCONFDIR)
  set(${out_var} "${absolute}/selfcal" PARENT_SCOPE)
endfunction()
