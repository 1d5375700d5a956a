#!/bin/bash
# The installed scan plans (config/daemon/plans/iiwa_SENSOR.yaml) are what `selfcal daemon-plan`
# makes of their cells (config/daemon/cells/iiwa_SENSOR.yaml), byte for byte, so that editing a
# cell and regenerating its plan is the documented way to a plan for another cell; selfcald
# --check accepts each with its sensor; a cell writes no truth.yaml, refuses --swap and cannot be
# simulated.
# Usage: installed_plans_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
source_dir=$(cd "$1" && pwd)
build_dir=$(cd "$2" && pwd)
work=$(mktemp -d /tmp/selfcal_installed_plans.XXXXXX)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
selfcal="$build_dir/tools/selfcal"
"$build_dir/daemon/selfcald" --generate-key "$work/daemon.key" >/dev/null

declare -A sensor_file=([hokuyo]=hokuyo_utm30lx [kinect]=kinect_azure_nfov_binned
                        [photoneo]=photoneo_motioncam3d [wenglor]=wenglor_mlsl236)
cd "$source_dir"  # the plans' first line names their cell by this relative path
for sensor in hokuyo kinect photoneo wenglor; do
  out="$work/$sensor"
  "$selfcal" -q daemon-plan "config/daemon/cells/iiwa_$sensor.yaml" --out "$out"
  cmp "$out/plan.yaml" "config/daemon/plans/iiwa_$sensor.yaml" ||
    fail "config/daemon/plans/iiwa_$sensor.yaml is not what its cell plans (run: selfcal daemon-plan config/daemon/cells/iiwa_$sensor.yaml --out DIR)"
  [ ! -e "$out/truth.yaml" ] || fail "daemon-plan wrote a truth.yaml for the real cell iiwa_$sensor"
  fit=$(grep -c 'purpose: fit' "$out/plan.yaml")
  validation=$(grep -c 'purpose: validation' "$out/plan.yaml")
  [ "$fit" = 28 ] && [ "$validation" = 7 ] || fail "iiwa_$sensor: $fit + $validation scans, not 28 + 7"
  cat >"$out/daemon.yaml" <<CONFIG
robot_id: cell-iiwa
lcm_url: "memq://"
robot_model: $source_dir/config/robots/kuka_lbr_iiwa_r840.yaml
sensor: $source_dir/config/sensors/${sensor_file[$sensor]}.yaml
plans: {$sensor: $source_dir/config/daemon/plans/iiwa_$sensor.yaml}
default_plan: $sensor
storage: {folder: storage, quota_mb: 10}
key_file: $work/daemon.key
acceptance: {noise_floor_m: 0.0077, min_improvement: 0.4}
CONFIG
  "$build_dir/daemon/selfcald" --check --config "$out/daemon.yaml" >"$out/check.log" 2>&1 ||
    { cat "$out/check.log"; fail "selfcald --check refuses the installed plan iiwa_$sensor"; }
done

# The shipped daemon configuration lists every installed plan, and selfcald checks them all.
for sensor in hokuyo kinect photoneo wenglor; do
  grep -q "^  $sensor: daemon/plans/iiwa_$sensor.yaml" config/daemon.yaml ||
    fail "config/daemon.yaml does not list the plan iiwa_$sensor"
done

if "$selfcal" -q daemon-plan config/daemon/cells/iiwa_hokuyo.yaml --out "$work/swap" --swap A4=0.5 2>"$work/swap.log"; then
  fail "daemon-plan --swap accepted a real cell"
fi
grep -q "describes a real cell" "$work/swap.log" || { cat "$work/swap.log"; fail "--swap on a cell: no reason"; }
if "$selfcal" -q simulate config/daemon/cells/iiwa_hokuyo.yaml --out "$work/sim" 2>"$work/sim.log"; then
  fail "simulate accepted a real cell"
fi
grep -q "cannot be simulated" "$work/sim.log" || { cat "$work/sim.log"; fail "simulate of a cell: no reason"; }
echo "installed plans: 4 cells plan their committed plans, 28 + 7 scans each, accepted by selfcald --check"
