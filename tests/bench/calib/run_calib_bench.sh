#!/bin/sh
# Engine benchmark: simulates (or reuses) scenarios, calibrates them with
# `selfcal calibrate`, and prints one machine-readable row per run:
#   scenario scans points iterations matches_per_iteration wall_s cpu_s peak_rss_mb load1
#   s_per_iteration nominal_mm nominal_deg calibrated_mm calibrated_deg solver termination
#   ratio_vs_reference ratio_per_iteration
# cpu_s is user + sys of the calibrate process; load1 is the 1-minute load average at its end
# (the machine is shared: read wall times next to it). ratio_* are reference / fast, measured in
# the same invocation (-r): total wall time, and mean seconds per ICP iteration.
# Usage: tests/bench/calib/run_calib_bench.sh [-b BUILD_DIR] [-d DATA_DIR] [-t THREADS] [-r]
#          [-i ICP_ITERATIONS] [-l LM_ITERATIONS] [-k SECONDS] [-a "OPTIONS"] SCENARIO:SCANS ...
#   SCENARIO:SCANS  e.g. kinect-bunny:28 small:14 field/hokuyo-office:28. Recordings are simulated once with 28 fit scans
#                   (+ the scenario's validation scans) into DATA_DIR/<scenario>/ and calibrated
#                   with --scans SCANS, so 7/14/21/28 rows share the same scans.
#   -r  also run --solver reference on the same data (first), for the ratio
#   -i/-l  cap ICP / Levenberg-Marquardt iterations (both solvers): the reference mode is too slow
#          for full runs on real scenarios, compare per iteration instead
#   -k  kill a calibration after this many seconds (default 900); its row says "killed"
#   -a  more `selfcal calibrate` options for every run (e.g. "--intrinsics auto --elasticity
#       --sensor-mass 0.37" for a field twin, docs/accuracy.md "The field table")
set -eu
root=$(cd "$(dirname "$0")/../../.." && pwd)
build=$root/build
data=${TMPDIR:-/tmp}/selfcal-bench
threads=0
reference=0
icp_iterations=0
lm_iterations=0
limit=900
extra=""
while getopts "b:d:t:ri:l:k:a:" option; do
  case $option in
    b) build=$OPTARG ;;
    d) data=$OPTARG ;;
    t) threads=$OPTARG ;;
    r) reference=1 ;;
    i) icp_iterations=$OPTARG ;;
    l) lm_iterations=$OPTARG ;;
    k) limit=$OPTARG ;;
    a) extra=$OPTARG ;;
    *) echo "error: unknown option (see the header of $0)" >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
selfcal=$build/tools/selfcal
[ -x "$selfcal" ] || { echo "error: $selfcal not built" >&2; exit 1; }
[ $# -gt 0 ] || { echo "error: no SCENARIO:SCANS given (see the header of $0)" >&2; exit 2; }
mkdir -p "$data"
cap=""  # capped runs keep their own files next to the full ones
[ "$icp_iterations$lm_iterations" = 00 ] || cap="-i$icp_iterations-l$lm_iterations"
echo "# bench: build=$build data=$data threads=$threads reference=$reference icp_iterations=$icp_iterations lm_iterations=$lm_iterations limit_s=$limit options=\"$extra\" host_cores=$(nproc) load=$(cut -d' ' -f1-3 /proc/loadavg)"
echo "scenario scans points iterations matches_per_iteration wall_s cpu_s peak_rss_mb load1 s_per_iteration nominal_mm nominal_deg calibrated_mm calibrated_deg solver termination ratio_vs_reference ratio_per_iteration"

run() {  # scenario scans solver -> prints a row; writes $dir/row-<scans>-<solver>.txt
  scenario=$1 scans=$2 solver=$3
  dir=$data/$scenario
  tag=$scans$cap-$solver
  out=$dir/result-$tag.yaml
  rm -f "$out"
  sensor=$(sed -n 's/^sensor: *\(\.\.\/\)*sensors\/\([^ #]*\).*/\2/p' "$root/config/scenarios/$scenario.yaml")
  /usr/bin/time -o "$dir/time-$tag.txt" -f "time: %e %U %S %M" timeout "$limit" "$selfcal" -q calibrate \
    --robot "$dir/nominal.yaml" --sensor "$root/config/sensors/$sensor" --log "$dir/recording.lcmlog" \
    --out "$out" --scans "$scans" --threads "$threads" --solver "$solver" --truth "$dir/truth.yaml" \
    --max-iterations "$icp_iterations" --lm-iterations "$lm_iterations" $extra >"$dir/calibrate-$tag.txt" 2>&1 || true
  load1=$(cut -d' ' -f1 /proc/loadavg)
  python3 - "$dir/calibrate-$tag.txt" "$dir/time-$tag.txt" "$out" "$scenario" "$scans" "$solver" "$load1" \
    "$dir/row-$scans$cap-reference.txt" "$dir/row-$tag.txt" <<'PY'
import os, re, sys, yaml
log, timing, out, scenario, scans, solver, load1, reference_row, own_row = sys.argv[1:10]
text = open(log).read()
t = re.search(r"time: ([\d.]+) ([\d.]+) ([\d.]+) (\d+)", open(timing).read())
wall, cpu, rss = float(t.group(1)), float(t.group(2)) + float(t.group(3)), int(t.group(4)) / 1024
pose = r"position rms +([\d.]+) mm .* orientation rms +([\d.]+) deg"
e = re.search(r"nominal +" + pose + r".*\n +calibrated +" + pose, text)
if os.path.exists(out):
    result = yaml.safe_load(open(out))["calibration"]
    matches = result["valid_matches_per_iteration"]
    seconds = [float(it["time_s"]) for it in result["per_iteration"]]
    row = dict(points=result["points"], iterations=result["iterations"],
               matches="%.0f" % (sum(matches) / len(matches)) if matches else "0",
               per_iteration="%.3f" % (sum(seconds) / len(seconds)) if seconds else "-",
               termination=result["termination"])
else:  # killed (-k) or failed before writing: no result file
    row = dict(points="-", iterations="-", matches="-", per_iteration="-",
               termination="killed" if "status 124" in open(timing).read() else "failed")
ratio = per_iteration_ratio = "-"
if solver == "fast" and os.path.exists(reference_row):
    ref = open(reference_row).read().split()
    ratio = "%.1f" % (float(ref[5]) / wall) if ref[15] != "killed" else "-"
    if ref[9] != "-" and row["per_iteration"] != "-":
        per_iteration_ratio = "%.1f" % (float(ref[9]) / float(row["per_iteration"]))
fields = [scenario, scans, row["points"], row["iterations"], row["matches"], "%.1f" % wall, "%.1f" % cpu,
          "%.0f" % rss, load1, row["per_iteration"]]
fields += list(e.groups()) if e else ["-"] * 4
fields += [solver, row["termination"], ratio, per_iteration_ratio]
line = " ".join(str(f) for f in fields)
open(own_row, "w").write(line + "\n")
print(line, flush=True)
PY
}

for item in "$@"; do
  scenario=${item%%:*}
  scans=${item#*:}
  dir=$data/$scenario
  [ -f "$root/config/scenarios/$scenario.yaml" ] || { echo "error: no config/scenarios/$scenario.yaml" >&2; exit 1; }
  if [ ! -f "$dir/recording.lcmlog" ]; then
    "$selfcal" -q simulate "$root/config/scenarios/$scenario.yaml" --scans 28 --out "$dir" >/dev/null
  fi
  rm -f "$dir/row-$scans$cap-reference.txt"
  if [ "$reference" = 1 ]; then
    run "$scenario" "$scans" reference
  fi
  run "$scenario" "$scans" fast
done
