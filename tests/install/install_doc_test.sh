#!/bin/bash
# Follows docs/install.md's tested steps in a temporary prefix: install, create the key, configure
# a Hokuyo named "front", verify its unit instance, plan scans from an installed cell, and run `selfcald --check` on the installed
# configuration (every file it names must exist in the prefix; nothing may be written).
# Exit 77 (skipped) when systemd-analyze is absent.
# Usage: install_doc_test.sh SOURCE_DIR BUILD_DIR
set -eu
source_dir=$1 build_dir=$2
if ! command -v systemd-analyze >/dev/null 2>&1; then
  echo "skipped: systemd-analyze is not installed"
  exit 77
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
prefix=$work/prefix
conf=$prefix/etc/selfcal
fail() { echo "FAIL: $*" >&2; exit 1; }
grep -q 'selfcald --generate-key CONF/daemon.key' "$source_dir/docs/install.md" ||
  fail "docs/install.md no longer shows the steps this test follows"

# 1. Build and install.
cmake --install "$build_dir" --prefix "$prefix" >"$work/install.log" 2>&1 ||
  { tail -n 20 "$work/install.log"; fail "cmake --install"; }
# 2. The key: mode 0600, never overwritten.
"$prefix/sbin/selfcald" --generate-key "$conf/daemon.key" >/dev/null || fail "--generate-key"
[ "$(stat -c %a "$conf/daemon.key")" = 600 ] || fail "the key is not mode 0600"
if "$prefix/sbin/selfcald" --generate-key "$conf/daemon.key" >/dev/null 2>&1; then
  fail "--generate-key overwrote an existing key"
fi
# 3. A Hokuyo named front.
cp "$conf/drivers/hokuyo.yaml" "$conf/drivers/hokuyo-front.yaml"
unit=$prefix/lib/systemd/system/selfcal-hokuyo@front.service
output=$(systemd-analyze verify "$unit" 2>&1) || fail "systemd-analyze verify $unit: $output"
[ -z "$output" ] || fail "systemd-analyze verify $unit warns: $output"
config=$(sed -n "s/^ExecStart=.*--config \([^ ]*\).*/\1/p" "${unit%front.service}.service" | sed "s/%i/front/")
[ -f "$config" ] || fail "the unit reads $config, which is not there"
# 4. A plan for this cell from the installed cell description (here unchanged, so it must be
# the installed plan but for the first comment line, which names the cell file).
"$prefix/bin/selfcal" -q daemon-plan "$conf/daemon/cells/iiwa_hokuyo.yaml" --out "$work/plan" ||
  fail "selfcal daemon-plan of the installed cell iiwa_hokuyo"
cmp -s <(tail -n +2 "$work/plan/plan.yaml") <(tail -n +2 "$conf/daemon/plans/iiwa_hokuyo.yaml") ||
  fail "the installed cell does not plan the installed plan iiwa_hokuyo"
# 5. The daemon's configuration, with the storage where this test may write, then --check.
sed -i "s|folder: /var/lib/selfcal|folder: $work/storage|" "$conf/daemon.yaml"
"$prefix/sbin/selfcald" --check --config "$conf/daemon.yaml" >"$work/check.log" 2>&1 ||
  { cat "$work/check.log"; fail "selfcald --check on the installed configuration"; }
for item in "key $conf/daemon.key" "sensor $conf/sensors/" "model $conf/robots/" "plan smoke ($conf/daemon/plans/" \
            "plan hokuyo (" "plan kinect (" "plan photoneo (" "plan wenglor ("; do
  grep -qF "$item" "$work/check.log" || { cat "$work/check.log"; fail "--check did not read: $item"; }
done
[ ! -e "$work/storage" ] || fail "selfcald --check wrote $work/storage"
echo "ok: installed, keyed, hokuyo-front verified, selfcald --check passed without writing"
