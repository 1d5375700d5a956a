#!/bin/sh
# `cmake --install` as a robot PC is set up, then checks what it wrote, for three layouts:
#   - a temporary prefix P (config in P/etc/selfcal);
#   - prefix /usr into a DESTDIR, as a package is built (config in /etc/selfcal, GNUInstallDirs);
#   - prefix /opt/robot into a DESTDIR (config in /etc/opt/robot/selfcal).
# For each:
# - nothing outside the prefix and its configuration folder (install_manifest.txt);
# - config/ is in the configuration folder the layout calls for;
# - every unit in systemd/ is installed, and `systemd-analyze verify` passes on each without a word
#   (units in a DESTDIR are verified with their paths moved into it, as systemd would see them);
# - every path an ExecStart names exists (the binary executable), %i aside, and lies under the
#   prefix or the configuration folder;
# - the default configuration paths compiled into the programs, moved from the configuration
#   folder they were built for to this installation's, exist;
# - each unit's exposure (`systemd-analyze security`) is at most the one docs/daemon.md records.
# Exit 77 (skipped) when systemd-analyze is absent.
# Usage: install_test.sh SOURCE_DIR BUILD_DIR BUILT_CONFIG_DIR
set -eu
source_dir=$1 build_dir=$2 built_config_dir=$3
if ! command -v systemd-analyze >/dev/null 2>&1; then
  echo "skipped: systemd-analyze is not installed"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }

# The highest exposure each unit may have (`systemd-analyze security --offline=yes`, systemd 252),
# as docs/daemon.md's table gives it: a change that loosens a unit's sandbox fails here, one that
# tightens it lowers the number here and in the table.
max_exposure() {
  case $1 in
    selfcald.service) echo 1.1 ;;
    selfcal-iiwa.service | selfcal-wenglor.service) echo 1.7 ;;
    selfcal-hokuyo@.service) echo 1.9 ;;
    selfcal-canopen.service) echo 2.0 ;;
    selfcal-aravis.service) echo 2.1 ;;
    selfcal-openni2.service | selfcal-v4l2.service) echo 2.2 ;;
  esac
}

# check_exposure NAME UNIT: the installed UNIT's exposure is within its bound.
check_exposure() {
  exposure=$(systemd-analyze security --offline=yes "$2" 2>/dev/null |
    sed -n 's/.*Overall exposure level for [^:]*: \([0-9.]*\).*/\1/p')
  bound=$(max_exposure "$1")
  if [ -z "$exposure" ]; then
    fail "systemd-analyze security --offline=yes printed no exposure level for $1"
  elif [ -z "$bound" ]; then
    fail "$1 has no exposure bound in max_exposure (add it, and its row in docs/daemon.md)"
  elif awk "BEGIN { exit !($exposure > $bound) }"; then
    fail "$1: exposure $exposure, above its bound $bound: its sandbox was loosened"
  else
    echo "ok: $1 (exposure $exposure, bound $bound)"
  fi
}

# check_install ROOT PREFIX CONFIG_DIR: install with DESTDIR=ROOT (empty: none) and --prefix
# PREFIX, expecting the configuration in CONFIG_DIR (as the units name it, without ROOT).
check_install() {
  root=$1 prefix=$2 config_dir=$3
  label="prefix $prefix${root:+ in DESTDIR}"
  if ! DESTDIR=$root cmake --install "$build_dir" --prefix "$prefix" >"$work/install.log" 2>&1; then
    tail -n 20 "$work/install.log" >&2
    echo "error: cmake --install ($label) failed" >&2
    exit 1
  fi
  outside=$(grep -v -e "^$prefix/" -e "^$config_dir/" "$build_dir/install_manifest.txt" || true)
  [ -z "$outside" ] || fail "$label: installed outside $prefix and $config_dir: $outside"
  for file in daemon.yaml robots/kuka_lbr_iiwa_r840.yaml drivers/canopen.yaml; do
    [ -f "$root$config_dir/$file" ] || fail "$label: $config_dir/$file is not installed"
  done

  unit_dir=$root$prefix/lib/systemd/system
  for template in "$source_dir"/systemd/*.service.in; do
    name=$(basename "$template" .in)
    [ -f "$unit_dir/$name" ] || fail "$label: $name is not installed in $unit_dir"
  done
  count=0
  for unit in "$unit_dir"/*.service; do
    [ -e "$unit" ] || continue
    name=$(basename "$unit")
    count=$((count + 1))
    # Every absolute path on an ExecStart line must lie in the prefix or the configuration folder
    # and exist there; the first word must be an installed executable.
    for path in $(sed -n 's/^ExecStart=[-@+!:]*//p' "$unit" | tr ' ' '\n' | grep '^/' || true); do
      case "$path" in *%*|*'$'*) continue ;; esac
      case "$path" in
        "$prefix"/* | "$config_dir"/*)
          [ -e "$root$path" ] || fail "$label: $name names $path, which is not installed" ;;
        *) fail "$label: $name names $path, outside $prefix and $config_dir" ;;
      esac
    done
    binary=$(sed -n 's/^ExecStart=[-@+!:]*\([^ ]*\).*/\1/p' "$unit" | head -n 1)
    [ -x "$root$binary" ] || fail "$label: $name runs $binary, which is not an installed executable"
    verified=$unit
    if [ -n "$root" ]; then
      mkdir -p "$work/moved"
      verified=$work/moved/$name
      # Only where a path starts (after a space, '=' or ':'): /opt/robot/ is also inside
      # /etc/opt/robot/selfcal/.
      sed -e "s#\([ =:]\)$config_dir/#\1$root$config_dir/#g" \
          -e "s#\([ =:]\)$prefix/#\1$root$prefix/#g" "$unit" >"$verified"
    fi
    if ! output=$(systemd-analyze verify "$verified" 2>&1); then
      fail "$label: systemd-analyze verify $name failed: $output"
    elif [ -n "$output" ]; then
      fail "$label: systemd-analyze verify $name warns: $output"
    elif [ -z "$root" ]; then
      check_exposure "$name" "$unit"
    fi
  done
  [ "$count" -gt 0 ] || fail "$label: no units in $unit_dir"

  # Default paths, as --help shows them, moved from the folder the programs were built for.
  for program in bin/selfcal-iiwa bin/selfcal-sim-fri bin/selfcal-canopen sbin/selfcald; do
    defaults=$("$root$prefix/$program" --help | grep -o "=$built_config_dir/[^ ]*" | sed 's/^=//' || true)
    [ -n "$defaults" ] || fail "$label: $program --help shows no default path under $built_config_dir"
    for path in $defaults; do
      moved=$root$config_dir${path#"$built_config_dir"}
      [ -e "$moved" ] || fail "$label: $program defaults to $path, which cmake --install does not write"
    done
  done
  echo "ok: $label: $count units verified, configuration in $config_dir"
}

check_install "" "$work/prefix" "$work/prefix/etc/selfcal"
check_install "$work/usr-root" /usr /etc/selfcal
check_install "$work/opt-root" /opt/robot /etc/opt/robot/selfcal
[ "$failures" -eq 0 ] || exit 1
echo "ok: cmake --install: every layout verified"
