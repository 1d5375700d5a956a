#!/bin/bash
# End to end, CI-sized: tools/demo's chain (FRI simulator + selfcal-iiwa, scene LiDAR, selfcald
# with the real engine, selfcal trigger) with 3 fitted and 1 validation scan. Passes when the
# session is accepted and the installed model's sensor pose error against the truth is below the
# nominal model's.
# Usage: daemon_e2e_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
source_dir=$1
build_dir=$2
log=$(mktemp /tmp/selfcal_e2e.XXXXXX.log)
trap 'rm -f "$log"' EXIT
if ! BUILD_DIR=$build_dir SELFCAL_DEMO_SKIP_SETUP=1 SELFCAL_DEMO_KEEP=1 SELFCAL_DEMO_SCANS=3 \
     SELFCAL_DEMO_VALIDATION=1 "$source_dir/tools/demo" >"$log" 2>&1; then
  cat "$log"
  echo "FAIL: the demo chain did not install a model" >&2
  exit 1
fi
cat "$log"
work=$(sed -n 's/^work folder: //p' "$log")
evaluate() { "$build_dir/tools/selfcal" -q evaluate --json --truth "$work/scenario/truth.yaml" --model "$1" |
             python3 -c 'import json,sys; d=json.load(sys.stdin); print(d["sensor"]["rms_position_mm"])'; }
nominal=$(evaluate "$work/scenario/nominal.yaml")
installed=$(evaluate "$work/storage/models/current/model.yaml")
echo "sensor position RMS against the truth: nominal $nominal mm, installed $installed mm"
rm -rf "$work"
python3 -c "import sys; sys.exit(0 if $installed < $nominal else 1)" || { echo "FAIL: no improvement" >&2; exit 1; }
