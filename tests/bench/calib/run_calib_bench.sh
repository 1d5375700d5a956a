#!/bin/sh
# Engine benchmark (issues 4, 5): simulates (or reuses) scenarios, calibrates them with
# `selfcal calibrate`, and prints one machine-readable row per run:
#   scenario scans points iterations matches_per_iteration wall_s cpu_s peak_rss_mb
#   nominal_mm nominal_deg calibrated_mm calibrated_deg solver ratio_vs_reference converged
# Usage: tests/bench/calib/run_calib_bench.sh [-b BUILD_DIR] [-d DATA_DIR] [-t THREADS] [-r]
#          SCENARIO:SCANS ...        (e.g. kinect-bunny:28 small:14; -r also runs --solver reference)
# Recordings are cached in DATA_DIR/<scenario>-<scans>/ (simulate writes them once).
set -eu
root=$(cd "$(dirname "$0")/../../.." && pwd)
build=$root/build
data=${TMPDIR:-/tmp}/selfcal-bench
threads=0
reference=0
while getopts "b:d:t:r" option; do
  case $option in
    b) build=$OPTARG ;;
    d) data=$OPTARG ;;
    t) threads=$OPTARG ;;
    r) reference=1 ;;
    *) echo "error: unknown option" >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
selfcal=$build/tools/selfcal
[ -x "$selfcal" ] || { echo "error: $selfcal not built" >&2; exit 1; }
mkdir -p "$data"
echo "# bench: build=$build data=$data threads=$threads reference=$reference host_cores=$(nproc)"
echo "scenario scans points iterations matches_per_iteration wall_s cpu_s peak_rss_mb nominal_mm nominal_deg calibrated_mm calibrated_deg solver ratio_vs_reference converged"

run() {  # scenario scans solver -> prints a row, sets last_wall
  scenario=$1 scans=$2 solver=$3
  dir=$data/$scenario-$scans
  out=$dir/result-$solver.yaml
  sensor=$(sed -n 's/^sensor: *\.\.\/sensors\/\([^ #]*\).*/\1/p' "$root/config/scenarios/$scenario.yaml")
  /usr/bin/time -f "time: %e %U %S %M" "$selfcal" -q calibrate --robot "$dir/nominal.yaml" \
    --sensor "$root/config/sensors/$sensor" --log "$dir/recording.lcmlog" --out "$out" \
    --threads "$threads" --solver "$solver" --truth "$dir/truth.yaml" >"$dir/calibrate-$solver.txt" 2>&1 || true
  python3 - "$dir/calibrate-$solver.txt" "$out" "$scenario" "$scans" "$solver" "${ref_wall:-}" <<'PY'
import re, sys, yaml
text = open(sys.argv[1]).read()
result = yaml.safe_load(open(sys.argv[2]))["calibration"]
t = re.search(r"time: ([\d.]+) ([\d.]+) ([\d.]+) (\d+)", text)
e = re.search(r"nominal ([\d.]+) mm ([\d.]+) deg -> calibrated ([\d.]+) mm ([\d.]+) deg", text)
matches = result["valid_matches_per_iteration"]
per_iteration = sum(matches) / len(matches) if matches else 0
wall = float(t.group(1))
ratio = "-"
if sys.argv[6] and sys.argv[5] == "fast":
    ratio = "%.1f" % (float(sys.argv[6]) / wall)
print(sys.argv[3], sys.argv[4], result["points"], result["iterations"], "%.0f" % per_iteration,
      "%.1f" % wall, "%.1f" % (float(t.group(2)) + float(t.group(3))), "%.0f" % (int(t.group(4)) / 1024),
      e.group(1), e.group(2), e.group(3), e.group(4), sys.argv[5], ratio, result["converged"])
PY
}

for item in "$@"; do
  scenario=${item%%:*}
  scans=${item#*:}
  dir=$data/$scenario-$scans
  if [ ! -f "$dir/recording.lcmlog" ]; then
    "$selfcal" -q simulate "$root/config/scenarios/$scenario.yaml" --scans "$scans" --out "$dir" >/dev/null
  fi
  ref_wall=""
  if [ "$reference" = 1 ]; then
    run "$scenario" "$scans" reference
    ref_wall=$(sed -n 's/^time: \([0-9.]*\) .*/\1/p' "$dir/calibrate-reference.txt")
  fi
  run "$scenario" "$scans" fast
done
