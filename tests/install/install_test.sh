#!/bin/sh
# `cmake --install` into a temporary prefix, as a robot PC is set up, then checks what it wrote:
# - nothing outside the prefix (install_manifest.txt);
# - every unit in systemd/ is installed, and `systemd-analyze verify` passes on each without a word;
# - every path an ExecStart names under the prefix exists (the binary executable), %i aside;
# - the default configuration paths compiled into the programs exist in the installed tree.
# Exit 77 (skipped) when systemd-analyze is absent.
# Usage: install_test.sh SOURCE_DIR BUILD_DIR CONFIGURED_PREFIX
set -eu
source_dir=$1 build_dir=$2 configured_prefix=$3
if ! command -v systemd-analyze >/dev/null 2>&1; then
  echo "skipped: systemd-analyze is not installed"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix
failures=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }

if ! cmake --install "$build_dir" --prefix "$prefix" >"$work/install.log" 2>&1; then
  tail -n 20 "$work/install.log" >&2
  echo "error: cmake --install failed" >&2
  exit 1
fi
outside=$(grep -v "^$prefix/" "$build_dir/install_manifest.txt" || true)
[ -z "$outside" ] || fail "installed outside the prefix: $outside"

unit_dir=$prefix/lib/systemd/system
for template in "$source_dir"/systemd/*.service.in; do
  name=$(basename "$template" .in)
  [ -f "$unit_dir/$name" ] || fail "$name is not installed in $unit_dir"
done
count=0
for unit in "$unit_dir"/*.service; do
  [ -e "$unit" ] || continue
  name=$(basename "$unit")
  count=$((count + 1))
  # Every absolute path on an ExecStart line that lies in the prefix must exist; the first word
  # must be an installed executable.
  for line in $(sed -n 's/^ExecStart=[-@+!:]*//p' "$unit" | tr ' ' '\n' | grep '^/' || true); do
    case "$line" in *%*|*'$'*) continue ;; esac
    case "$line" in
      "$prefix"/*) [ -e "$line" ] || fail "$name names $line, which is not installed" ;;
      *) fail "$name names $line, outside the prefix $prefix" ;;
    esac
  done
  binary=$(sed -n 's/^ExecStart=[-@+!:]*\([^ ]*\).*/\1/p' "$unit" | head -n 1)
  [ -x "$binary" ] || fail "$name runs $binary, which is not an installed executable"
  if ! output=$(systemd-analyze verify "$unit" 2>&1); then
    fail "systemd-analyze verify $name failed: $output"
  elif [ -n "$output" ]; then
    fail "systemd-analyze verify $name warns: $output"
  else
    # Exposure for the record (docs/daemon.md); informational, not a pass criterion.
    exposure=$(systemd-analyze security --offline=yes "$unit" 2>/dev/null | grep -o 'Overall exposure level.*' || true)
    echo "ok: $name ${exposure:+($exposure)}"
  fi
done
[ "$count" -gt 0 ] || fail "no units in $unit_dir"

# Default paths: what --help shows, moved from the configured prefix to this one.
for program in bin/selfcal-iiwa bin/selfcal-sim-fri bin/selfcal-canopen sbin/selfcald; do
  defaults=$("$prefix/$program" --help | grep -o "=$configured_prefix/[^ ]*" | sed 's/^=//' || true)
  [ -n "$defaults" ] || fail "$program --help shows no default path under $configured_prefix"
  for path in $defaults; do
    moved=$prefix${path#"$configured_prefix"}
    [ -e "$moved" ] || fail "$program defaults to $path, which cmake --install does not write"
  done
  echo "ok: $program defaults: $defaults"
done
[ "$failures" -eq 0 ] || exit 1
echo "ok: cmake --install --prefix: $count units verified"
