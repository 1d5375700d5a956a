#!/bin/sh
# Engine variants on one recording, measured in the same run: calibrates DIR (a `selfcal simulate`
# output) once per VARIANT (extra `selfcal calibrate` arguments, e.g. "--border-rule surface"; the
# first is the baseline) and prints one row per variant with wall and CPU time, iterations, the
# sensor pose error against DIR/truth.yaml and the ratios of wall and CPU time to the baseline.
# Usage: tests/bench/calib/run_variants_bench.sh [-b BUILD] [-t THREADS] [-n SCANS]
#          DIR SENSOR.yaml VARIANT...
# e.g. tests/bench/calib/run_variants_bench.sh -t 2 /tmp/kb config/sensors/kinect_azure_nfov_binned.yaml \
#        "--border-rule off" "--border-rule surface"
# Never run by ctest; docs/accuracy.md and docs/performance.md hold what it measured.
set -eu
root=$(cd "$(dirname "$0")/../../.." && pwd)
build=$root/build
threads=0
scans=0
while getopts "b:t:n:" option; do
  case $option in
    b) build=$OPTARG ;;
    t) threads=$OPTARG ;;
    n) scans=$OPTARG ;;
    *) echo "error: unknown option (see the header of $0)" >&2; exit 2 ;;
  esac
done
shift $((OPTIND - 1))
[ $# -ge 3 ] || { echo "error: need DIR SENSOR and at least one VARIANT (see the header of $0)" >&2; exit 2; }
dir=$1 sensor=$2
shift 2
selfcal=$build/tools/selfcal
[ -x "$selfcal" ] || { echo "error: $selfcal not built" >&2; exit 1; }
echo "# variants: dir=$dir sensor=$sensor scans=$scans threads=$threads host_cores=$(nproc) load=$(cut -d' ' -f1-3 /proc/loadavg)"
echo "variant | wall_s cpu_s | iterations termination | position_mm orientation_deg | wall_ratio cpu_ratio load1"
base_wall="" base_cpu=""
index=0
for variant in "$@"; do
  index=$((index + 1))
  out=$dir/variant-$index.yaml
  # shellcheck disable=SC2086  # a variant is a list of arguments
  /usr/bin/time -o "$dir/variant-$index.time" -f "%e %U %S" "$selfcal" -q calibrate --robot "$dir/nominal.yaml" \
    --sensor "$sensor" --log "$dir/recording.lcmlog" --out "$out" --truth "$dir/truth.yaml" \
    --threads "$threads" --scans "$scans" $variant >"$dir/variant-$index.txt" 2>&1 || true
  read -r wall user system <"$dir/variant-$index.time"
  cpu=$(echo "$user $system" | awk '{printf "%.2f", $1 + $2}')
  [ -n "$base_wall" ] || { base_wall=$wall; base_cpu=$cpu; }
  error=$(sed -n 's/^ *calibrated position rms *\([0-9.]*\) mm.*orientation rms *\([0-9.]*\) deg.*/\1 \2/p' "$dir/variant-$index.txt")
  iterations=$(sed -n 's/^iterations: \([0-9]*\),.*/\1/p' "$dir/variant-$index.txt")
  termination=$(sed -n 's/^termination: \([a-z_]*\).*/\1/p' "$dir/variant-$index.txt")
  echo "$variant | $wall $cpu | ${iterations:--} ${termination:--} | ${error:-- -} | $(echo "$wall $base_wall $cpu $base_cpu" | awk '{printf "%.2f %.2f", $1 / $2, $3 / $4}') $(cut -d' ' -f1 /proc/loadavg)"
done
