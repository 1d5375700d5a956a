# Toolchain file: arm64 (aarch64) with Debian's cross toolchain (crossbuild-essential-arm64),
# against the multiarch :arm64 libraries in /usr/lib/aarch64-linux-gnu. tools/cross-arm64 installs
# all of it and uses this file; tests run under qemu-user (CMAKE_CROSSCOMPILING_EMULATOR for the
# test executables, binfmt_misc for the programs they start).
#
# Debian packages an arm64 library that is not Multi-Arch: same (liblcm1, liblcm-dev,
# libyaml-cpp-dev) cannot be installed beside its amd64 twin; tools/cross-arm64 unpacks those into
# SELFCAL_ARM64_EXTRA_ROOT (environment or -D; default /opt/selfcal-arm64), searched here too.
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

if(NOT SELFCAL_ARM64_EXTRA_ROOT)
  if(DEFINED ENV{SELFCAL_ARM64_EXTRA_ROOT})
    set(SELFCAL_ARM64_EXTRA_ROOT "$ENV{SELFCAL_ARM64_EXTRA_ROOT}")
  else()
    set(SELFCAL_ARM64_EXTRA_ROOT /opt/selfcal-arm64)
  endif()
endif()
list(APPEND CMAKE_PREFIX_PATH ${SELFCAL_ARM64_EXTRA_ROOT}/usr)

# pkg-config reads the arm64 .pc files only, never the build machine's.
set(ENV{PKG_CONFIG_LIBDIR}
    "${SELFCAL_ARM64_EXTRA_ROOT}/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/lib/aarch64-linux-gnu/pkgconfig:/usr/share/pkgconfig")
unset(ENV{PKG_CONFIG_PATH})

# Programs run at build time (lcm-gen) are the build machine's; libraries and packages arm64's.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)

find_program(SELFCAL_QEMU_AARCH64 NAMES qemu-aarch64-static qemu-aarch64)
if(SELFCAL_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${SELFCAL_QEMU_AARCH64})
endif()
