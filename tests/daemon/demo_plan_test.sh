#!/bin/bash
# The demo's scan plan (config/scenarios/hokuyo-demo.yaml through `selfcal daemon-plan`) is what
# docs/daemon.md says and what selfcald accepts: 8 fitted + 2 validation sweeps, within the iiwa's
# joint and velocity limits (selfcald --check runs the daemon's plan check). The same scenario at
# line_spacing 8 sweeps at 1.40 rad/s, above A4's 1.309 rad/s: the check must refuse it, which
# is why the demo uses 7. `selfcald --check` writes nothing. `tools/demo --remaster`'s plan
# (`daemon-plan --mode remaster --swap A4=0.5`): 6 fitted + 2 validation sweeps of the same
# plan, `mode: remaster`, the same truth before the swap (installed.yaml), accepted by selfcald;
# `selfcal trigger --mode` picks it, or refuses clearly before sending anything.
# Usage: demo_plan_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
source_dir=$(cd "$1" && pwd)
build_dir=$2
work=$(mktemp -d /tmp/selfcal_demo_plan.XXXXXX)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

check() {  # SCENARIO FOLDER: daemon-plan, then selfcald --check on a configuration using it
  "$build_dir/tools/selfcal" -q daemon-plan "$1" --out "$2"
  [ -f "$work/daemon.key" ] || "$build_dir/daemon/selfcald" --generate-key "$work/daemon.key" >/dev/null
  cat >"$2/daemon.yaml" <<CONFIG
robot_id: demo-iiwa
lcm_url: "memq://"
robot_model: nominal.yaml
sensor: $source_dir/config/sensors/hokuyo_utm30lx.yaml
plans: {demo: plan.yaml}
default_plan: demo
storage: {folder: storage, quota_mb: 10}
key_file: $work/daemon.key
acceptance: {noise_floor_m: 0.0077, min_improvement: 0.4}
CONFIG
  "$build_dir/daemon/selfcald" --check --config "$2/daemon.yaml" >"$2/check.log" 2>&1
}

check "$source_dir/config/scenarios/hokuyo-demo.yaml" "$work/demo" || { cat "$work/demo/check.log"; fail "selfcald refuses the demo plan"; }
# A check writes nothing: the storage folder it would create does not appear.
[ ! -e "$work/demo/storage" ] || fail "selfcald --check created $work/demo/storage"
grep -q "storage $work/demo/storage: does not exist yet; .* is writable, the daemon will create it" "$work/demo/check.log" ||
  { cat "$work/demo/check.log"; fail "selfcald --check does not report the storage folder"; }
fit=$(grep -c 'purpose: fit' "$work/demo/plan.yaml")
validation=$(grep -c 'purpose: validation' "$work/demo/plan.yaml")
[ "$fit" = 8 ] && [ "$validation" = 2 ] || fail "the demo plan has $fit + $validation sweeps, not 8 + 2"
# Peak sweep speed 7 x 0.25 deg per 25 ms rotation = 1.2217 rad/s.
python3 - "$work/demo/plan.yaml" <<'PY' || fail "sweep speeds are not 1.2217 rad/s"
import re, sys
speeds = [float(s) for s in re.findall(r"speed: ([0-9.eE+-]+)", open(sys.argv[1]).read())]
sys.exit(0 if speeds and all(abs(s - 1.2217) < 1e-3 for s in speeds) else 1)
PY

# tools/demo's default, the field twin, plans the same sweeps and the same true and nominal arm.
"$build_dir/tools/selfcal" -q daemon-plan "$source_dir/config/scenarios/field/hokuyo-demo.yaml" --out "$work/field"
for file in plan.yaml nominal.yaml truth.yaml; do
  cmp -s <(grep -vE '^#|^name:|scenario:' "$work/demo/$file") <(grep -vE '^#|^name:|scenario:' "$work/field/$file") ||
    fail "the field demo's $file differs from hokuyo-demo's"
done
grep -q '^effects:' "$work/field/scenario.yaml" || fail "the field demo's resolved scenario has no effects"

# The remastering's plan: the first 6 fitted sweeps and the same validation ones, mode remaster.
"$build_dir/tools/selfcal" -q daemon-plan "$source_dir/config/scenarios/field/hokuyo-demo.yaml" \
  --out "$work/remaster" --mode remaster --swap A4=0.5
grep -q '^mode: remaster' "$work/remaster/plan.yaml" || fail "the remaster plan has no 'mode: remaster'"
fit=$(grep -c 'purpose: fit' "$work/remaster/plan.yaml")
validation=$(grep -c 'purpose: validation' "$work/remaster/plan.yaml")
[ "$fit" = 6 ] && [ "$validation" = 2 ] || fail "the remaster plan has $fit + $validation sweeps, not 6 + 2"
cmp -s <(grep 'purpose: validation' "$work/remaster/plan.yaml") <(grep 'purpose: validation' "$work/field/plan.yaml") ||
  fail "the remaster plan's validation sweeps differ from the demo's"
cmp -s <(grep 'purpose: fit' "$work/remaster/plan.yaml") <(grep 'purpose: fit' "$work/field/plan.yaml" | head -n 6) ||
  fail "the remaster plan's fitted sweeps are not the demo's first 6"
# The truth before the swap, with the sag the field twin's joint elasticity gives it (the truth
# files stay rigid): a model calibrated with elasticity, as a site would have installed.
rigid='^#|role:|scenario:|sensor_mass_kg:|compliance_rad_per_nm:'
cmp -s <(grep -vE "$rigid" "$work/remaster/installed.yaml") <(grep -vE "$rigid" "$work/field/truth.yaml") ||
  fail "installed.yaml is not the field demo's truth before the swap"
grep -q '^  compliance_rad_per_nm: \[5.0000000000000002e-05, ' "$work/remaster/installed.yaml" &&
  grep -q '^  sensor_mass_kg: 0.37' "$work/remaster/installed.yaml" ||
  fail "installed.yaml lacks the field twin's joint elasticity (compliance, sensor mass)"
! grep -q 'compliance_rad_per_nm' "$work/field/truth.yaml" || fail "truth.yaml is not the rigid arm"
grep -q '^  joint_offsets: \[0, 0, 0, 0.0087266462599716' "$work/remaster/scenario.yaml" ||
  fail "the resolved scenario does not carry the swap as truth.joint_offsets"
sed -e 's|robot_model: nominal.yaml|robot_model: installed.yaml|' \
    -e 's|plans: {demo: plan.yaml}|plans: {demo: ../field/plan.yaml, remaster: plan.yaml}|' \
    "$work/demo/daemon.yaml" >"$work/remaster/daemon.yaml"
"$build_dir/daemon/selfcald" --check --config "$work/remaster/daemon.yaml" >"$work/remaster/check.log" 2>&1 ||
  { cat "$work/remaster/check.log"; fail "selfcald refuses the remaster plan"; }
trigger() { "$build_dir/tools/selfcal" trigger --timeout 0.5 --no-wait "$@" 2>&1 || true; }
trigger -c "$work/demo/daemon.yaml" --mode remaster | grep -q "has no remaster plan" ||
  fail "trigger --mode remaster without a remaster plan does not say so"
trigger -c "$work/remaster/daemon.yaml" --mode remaster --plan demo | grep -q "plan demo (.*) is a full plan, not a remaster one" ||
  fail "trigger --mode remaster --plan demo does not refuse the full plan"
trigger -c "$work/remaster/daemon.yaml" --mode remaster | grep -q "no answer from selfcald" ||
  fail "trigger --mode remaster with one remaster plan did not send its request"

sed -e 's/line_spacing: 7/line_spacing: 8/' -e "s|\.\./|$source_dir/config/|g" \
  "$source_dir/config/scenarios/hokuyo-demo.yaml" >"$work/spacing8.yaml"
if check "$work/spacing8.yaml" "$work/spacing8"; then fail "selfcald accepted sweeps beyond A4's velocity limit"; fi
grep -q "exceeds the velocity limit" "$work/spacing8/check.log" || { cat "$work/spacing8/check.log"; fail "no velocity-limit reason"; }
echo "demo plan: 8 + 2 sweeps, within limits; line_spacing 8 refused; the field twin plans the same; the remaster plan 6 + 2"
