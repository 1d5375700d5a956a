#!/bin/sh
# `systemd-analyze verify` on every unit in systemd/. The units name installed paths
# (/usr/local/sbin/..., /usr/bin/...); this test points them at the binaries of this build, which is all
# verify needs to find. Exit 77 (skipped) when systemd-analyze is absent.
# Usage: systemd_verify_test.sh SOURCE_DIR BUILD_DIR
set -eu
source_dir=$1
build_dir=$2
if ! command -v systemd-analyze >/dev/null 2>&1; then
  echo "skipped: systemd-analyze is not installed"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
count=0
for unit in "$source_dir"/systemd/*.service; do
  [ -e "$unit" ] || continue
  name=$(basename "$unit")
  sed_script=""
  for path in $(grep -oE '/usr/(local/)?s?bin/[A-Za-z0-9_.-]+' "$unit" | sort -u); do
    binary=$(find "$build_dir" -type f -perm -u+x -name "$(basename "$path")" -not -path '*/CMakeFiles/*' | head -n 1)
    if [ -z "$binary" ]; then
      echo "error: $name runs $path, which this build does not produce" >&2
      exit 1
    fi
    sed_script="$sed_script -e s|$path|$binary|g"
  done
  # shellcheck disable=SC2086
  sed $sed_script "$unit" >"$work/$name"
  if ! output=$(systemd-analyze verify "$work/$name" 2>&1); then
    echo "error: systemd-analyze verify $name failed:" >&2
    echo "$output" >&2
    exit 1
  fi
  if [ -n "$output" ]; then
    echo "error: systemd-analyze verify $name warns:" >&2
    echo "$output" >&2
    exit 1
  fi
  # Exposure for the record (docs/daemon.md); informational, not a pass criterion.
  exposure=$(systemd-analyze security --offline=yes "$work/$name" 2>/dev/null | grep -o 'Overall exposure level.*' || true)
  echo "ok: $name ${exposure:+($exposure)}"
  count=$((count + 1))
done
[ "$count" -gt 0 ] || { echo "error: no units in $source_dir/systemd" >&2; exit 1; }
