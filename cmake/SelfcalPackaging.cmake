# Debian packages, one per install component, by CPack's DEB generator (tools/package builds
# them; docs/packaging.md says why CPack and what each package holds). The packages are made from
# the same install rules as `cmake --install`, so paths, units and configuration have one home
# (cmake/SelfcalConfigDir.cmake, systemd/CMakeLists.txt). Included after every subdirectory, so
# that the parts of systemd/CMakeLists.txt are known.
option(SELFCAL_DEBIAN_PACKAGE
       "Add what a Debian package needs (copyright, changelog, maintainer scripts) and CPack's DEB setup"
       OFF)
if(NOT SELFCAL_DEBIAN_PACKAGE)
  return()
endif()
if(NOT SELFCAL_BUILD_ENGINE)
  message(FATAL_ERROR "SELFCAL_DEBIAN_PACKAGE needs SELFCAL_BUILD_ENGINE (the selfcal and selfcald "
                      "packages hold the engine)")
endif()
if(NOT CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  message(FATAL_ERROR "SELFCAL_DEBIAN_PACKAGE needs -DCMAKE_INSTALL_PREFIX=/usr, not "
                      "${CMAKE_INSTALL_PREFIX} (the programs compile in their configuration folder)")
endif()

set(SELFCAL_DEBIAN_MAINTAINER "selfcal maintainers <selfcal@example.org>" CACHE STRING
    "The Maintainer: of the Debian packages (name <address>); a site sets its own")
set(packaging_dir "${PROJECT_SOURCE_DIR}/packaging/debian")
set(control_dir "${PROJECT_BINARY_DIR}/packaging")

# The changelog every package carries (lintian: compressed with gzip -9n).
configure_file("${packaging_dir}/changelog.in" "${control_dir}/changelog" @ONLY)
execute_process(COMMAND gzip -9nc "${control_dir}/changelog"
                OUTPUT_FILE "${control_dir}/changelog.gz" COMMAND_ERROR_IS_FATAL ANY)

# Writes COMPONENT's control files (conffiles, maintainer scripts) to control_dir/COMPONENT and
# sets CPack's variables for it; the names of its control files go to OUT_VAR.
function(_selfcal_debian_control_files component package out_var)
  set(dir "${control_dir}/${component}")
  file(MAKE_DIRECTORY "${dir}")
  set(files "")
  # Every file installed to the configuration folder is a conffile.
  get_property(entries GLOBAL PROPERTY SELFCAL_PART_CONFIG_${component})
  set(conffiles "")
  foreach(entry IN LISTS entries)
    set(source "${PROJECT_SOURCE_DIR}/config/${entry}")
    if(IS_DIRECTORY "${source}")
      file(GLOB_RECURSE found LIST_DIRECTORIES false CONFIGURE_DEPENDS RELATIVE
           "${PROJECT_SOURCE_DIR}/config" "${source}/*")
      list(SORT found)
    else()
      set(found "${entry}")
    endif()
    foreach(file IN LISTS found)
      string(APPEND conffiles "${SELFCAL_CONFIG_DIR}/${file}\n")
    endforeach()
  endforeach()
  if(conffiles)
    file(WRITE "${dir}/conffiles" "${conffiles}")
    list(APPEND files "${dir}/conffiles")
  endif()
  # Maintainer scripts: for the units (reload, stop on removal, restart on upgrade) and the extras
  # of packaging/debian/PACKAGE.postinst-configure and PACKAGE.postrm-purge.
  get_property(UNITS GLOBAL PROPERTY SELFCAL_PART_UNITS_${component})
  set(POSTINST_CONFIGURE "")
  set(POSTRM_PURGE "")
  if(EXISTS "${packaging_dir}/${package}.postinst-configure")
    file(READ "${packaging_dir}/${package}.postinst-configure" POSTINST_CONFIGURE)
  endif()
  if(EXISTS "${packaging_dir}/${package}.postrm-purge")
    file(READ "${packaging_dir}/${package}.postrm-purge" POSTRM_PURGE)
  endif()
  if(UNITS OR POSTINST_CONFIGURE OR POSTRM_PURGE)
    set(PACKAGE "${package}")
    string(REPLACE "@.service" "@*.service" UNIT_PATTERNS "${UNITS}")
    string(REPLACE ";" " " UNIT_PATTERNS "${UNIT_PATTERNS}")
    string(REPLACE ";" " " UNITS "${UNITS}")
    foreach(script postinst prerm postrm)
      configure_file("${packaging_dir}/${script}.in" "${dir}/${script}" @ONLY
                     FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ
                                      GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
      list(APPEND files "${dir}/${script}")
    endforeach()
  endif()
  set(${out_var} "${files}" PARENT_SCOPE)
endfunction()

# selfcal_debian_package(COMPONENT NAME package SUMMARY line DESCRIPTION text
#                        [DEPENDS component...] [EXTRA_DEPENDS "pkg, pkg"] [ALL])
# ALL: Architecture: all (no binaries). Depends: the packages of DEPENDS at this version, the
# EXTRA_DEPENDS, and what dpkg-shlibdeps finds for the binaries.
set(SELFCAL_DEBIAN_COMPONENTS "")
# (A macro, for CPack's variables: no ';' in SUMMARY or DESCRIPTION, it would split them.)
macro(selfcal_debian_package component)
  cmake_parse_arguments(DEB "ALL" "NAME;SUMMARY;DESCRIPTION;EXTRA_DEPENDS" "DEPENDS" ${ARGN})
  string(TOUPPER "${component}" upper)
  list(APPEND SELFCAL_DEBIAN_COMPONENTS ${component})
  set(CPACK_DEBIAN_${upper}_PACKAGE_NAME "${DEB_NAME}")
  set(CPACK_COMPONENT_${upper}_DESCRIPTION "${DEB_SUMMARY}\n${DEB_DESCRIPTION}")
  set(CPACK_COMPONENT_${upper}_DEPENDS ${DEB_DEPENDS})
  if(DEB_EXTRA_DEPENDS)
    set(CPACK_DEBIAN_${upper}_PACKAGE_DEPENDS "${DEB_EXTRA_DEPENDS}")
  endif()
  if(DEB_ALL)
    set(CPACK_DEBIAN_${upper}_PACKAGE_ARCHITECTURE all)
  endif()
  _selfcal_debian_control_files(${component} ${DEB_NAME} control_files)
  set(CPACK_DEBIAN_${upper}_PACKAGE_CONTROL_EXTRA "${control_files}")
  set(CPACK_DEBIAN_${upper}_PACKAGE_CONTROL_STRICT_PERMISSION TRUE)
  install(FILES "${packaging_dir}/copyright" "${control_dir}/changelog.gz"
          DESTINATION "${CMAKE_INSTALL_DATAROOTDIR}/doc/${DEB_NAME}" COMPONENT ${component})
endmacro()

selfcal_debian_package(common NAME selfcal-common ALL
  SUMMARY "robot self-calibration: shared configuration and documents"
  DESCRIPTION "Robot models, sensor files (the paper's Table I values), simulation
scenarios and the LCM channel names in /etc/selfcal, read by the command
line, the daemon and the drivers. The documents the units point at.")
selfcal_debian_package(cli NAME selfcal DEPENDS common
  EXTRA_DEPENDS "libjs-three, libjs-chart.js"  # inlined into reports (docs/report.md)
  SUMMARY "robot self-calibration: command line and calibration engine"
  DESCRIPTION "The selfcal command: simulate a robot cell, calibrate a kinematic model from
a recording (ICP bundle adjustment over the scans of an actuated 3D sensor),
evaluate, export and import models, and trigger, follow and roll back the
daemon's calibrations.")
selfcal_debian_package(daemon NAME selfcald DEPENDS common
  EXTRA_DEPENDS "adduser, libjs-three, libjs-chart.js"  # libjs: the session reports
  SUMMARY "robot self-calibration: calibration daemon"
  DESCRIPTION "selfcald runs under systemd as the system user selfcal: on a signed LCM
request it moves the arm through scan plans, records the sensor, calibrates,
validates on held-back scans and only then installs the new model. Its
configuration is /etc/selfcal/daemon.yaml. The request key
/etc/selfcal/daemon.key is made on installation.")
selfcal_debian_package(hokuyo NAME selfcal-hokuyo DEPENDS common
  SUMMARY "robot self-calibration: Hokuyo SCIP 2.0 LiDAR driver"
  DESCRIPTION "selfcal-hokuyo streams the scans of a Hokuyo UTM-30LX or another SCIP 2.0
sensor (serial, USB or TCP) over LCM with device-clock time stamps. One unit
instance per sensor, selfcal-hokuyo@NAME.service.")
selfcal_debian_package(iiwa NAME selfcal-iiwa DEPENDS common
  SUMMARY "robot self-calibration: KUKA LBR iiwa FRI client"
  DESCRIPTION "selfcal-iiwa publishes the joint states of a KUKA LBR iiwa over LCM and
executes the daemon's scan trajectories through the Fast Robot Interface.")
selfcal_debian_package(canopen NAME selfcal-canopen DEPENDS common
  SUMMARY "robot self-calibration: CANopen (CiA 402) joint state driver"
  DESCRIPTION "selfcal-canopen reads the joint positions of a CANopen arm over SocketCAN
and publishes them over LCM. Configuration in
/etc/selfcal/drivers/canopen.yaml.")
selfcal_debian_package(wenglor NAME selfcal-wenglor DEPENDS common
  SUMMARY "robot self-calibration: Wenglor weCat3D line scanner driver"
  DESCRIPTION "selfcal-wenglor publishes the profiles of a Wenglor weCat3D line scanner
over LCM. It loads the vendor's EthernetScanner library at run time. That
library is not part of Debian.")
selfcal_debian_package(aravis NAME selfcal-aravis DEPENDS common
  SUMMARY "robot self-calibration: GigE Vision 3D camera driver (Aravis)"
  DESCRIPTION "selfcal-aravis publishes the organized point clouds of a PhotoNeo
MotionCam-3D or PhoXi (GenICam over GigE Vision) over LCM.")
selfcal_debian_package(openni2 NAME selfcal-openni2 DEPENDS common
  SUMMARY "robot self-calibration: OpenNI2 depth camera driver"
  DESCRIPTION "selfcal-openni2 publishes the depth images of a Kinect or another OpenNI2
camera over LCM.")
selfcal_debian_package(v4l2 NAME selfcal-v4l2 DEPENDS common
  SUMMARY "robot self-calibration: V4L2 (UVC Z16) depth camera driver"
  DESCRIPTION "selfcal-v4l2 publishes the depth images of a UVC depth camera (Z16) over
LCM.")
selfcal_debian_package(sim NAME selfcal-sim DEPENDS common
  SUMMARY "robot self-calibration: device simulators"
  DESCRIPTION "Simulated devices for tests and demonstrations: a SCIP 2.0 LiDAR
(selfcal-sim-scip), a KUKA FRI controller (selfcal-sim-fri) and a scene
LiDAR over LCM (selfcal-sim-scene-lidar). Not needed on a robot.")

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME selfcal)
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_CONTACT "${SELFCAL_DEBIAN_MAINTAINER}")
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "${SELFCAL_DEBIAN_MAINTAINER}")
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL ${SELFCAL_DEBIAN_COMPONENTS})
set(CPACK_DEBIAN_ENABLE_COMPONENT_DEPENDS ON)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
# Installed with DESTDIR and the real prefix, so that the units name /usr, not the staging folder.
set(CPACK_SET_DESTDIR ON)
set(CPACK_STRIP_FILES ON)
set(CPACK_OUTPUT_FILE_PREFIX packages)
include(CPack)
