#!/bin/bash
# The flood of forged requests against selfcald (daemon_flood_bench.cc says what it sends and
# measures), in a fresh network namespace: selfcald with the scripted engine, the TestArm as arm
# and sensor, everything over udpm:// on the namespace's loopback.
# Usage: daemon_flood_bench.sh SOURCE_DIR BUILD_DIR [SECONDS [RATE [BENCH OPTIONS...]]]
#   e.g. daemon_flood_bench.sh . build 30 1000            (the benchmark, prints numbers)
#        daemon_flood_bench.sh . build 6 1000 --check     (the short version, as a test)
set -euo pipefail
source_dir=$(cd "$1" && pwd)
build_dir=$(cd "$2" && pwd)
seconds=${3:-30}
rate=${4:-1000}
shift $(($# < 4 ? $# : 4))
if [ -z "${SELFCAL_IN_NETNS:-}" ]; then
  SELFCAL_IN_NETNS=1 exec "$source_dir/tests/netns-run" "$0" "$source_dir" "$build_dir" \
    "$seconds" "$rate" "$@"
fi
selfcald=$build_dir/tests/daemon/selfcald_scripted
arm=$build_dir/tests/daemon/selfcal_test_arm
bench=$build_dir/tests/bench/daemon/daemon_flood_bench
cli=$build_dir/tools/selfcal
work=$(mktemp -d /tmp/selfcal_daemon_flood.XXXXXX)
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608"
daemon_pid=""
arm_pid=""
cleanup() {
  [ -n "$daemon_pid" ] && kill "$daemon_pid" 2>/dev/null || true
  [ -n "$arm_pid" ] && kill "$arm_pid" 2>/dev/null || true
  wait 2>/dev/null || true
  if [ "${keep_work:-0}" = 1 ]; then echo "work folder kept: $work"; else rm -rf "$work"; fi
}
trap cleanup EXIT

# One session of about 4 s of motion; the scripted engine computes for 1 s.
cat >"$work/tiny.yaml" <<'PLAN'
name: tiny
scans:
  - {purpose: fit, from: [0.0, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0], to: [0.4, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0], speed: 0.4}
  - {purpose: fit, from: [0.4, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0], to: [0.4, 0.5, 0.0, -1.2, 0.0, 0.8, 0.4], speed: 0.4}
  - {purpose: validation, from: [0.4, 0.4, 0.0, -1.2, 0.0, 0.8, 0.4], to: [0.4, 0.4, 0.0, -1.2, 0.4, 0.8, 0.4], speed: 0.4}
PLAN
cat >"$work/daemon.yaml" <<CONFIG
robot_id: test-arm
lcm_url: "$url"
robot_model: $source_dir/config/robots/kuka_lbr_iiwa_r840.yaml
sensor: $source_dir/config/sensors/hokuyo_utm30lx.yaml
plans: {tiny: tiny.yaml}
default_plan: tiny
storage: {folder: storage, quota_mb: 100}
key_file: daemon.key
checks: {joint_state_max_age_s: 0.2, sensor_max_age_s: 0.5, max_deviation: 0.05}
motion: {speed_fraction: 1.0, settle_time_s: 0.1}
acceptance: {min_improvement: 0.05, max_angle_change_rad: 0.05, max_translation_change_m: 0.05}
CONFIG
"$selfcald" --generate-key "$work/daemon.key" >/dev/null
"$arm" --lcm-url "$url" &
arm_pid=$!
# SELFCAL_FLOOD_WRAP: a command the daemon runs under (strace -f -o FILE: its system calls).
SELFCAL_TEST_ENGINE="seconds=1,rms_before=0.010,rms_after=0.004" ${SELFCAL_FLOOD_WRAP:-} \
  "$selfcald" -c "$work/daemon.yaml" >"$work/daemon.log" 2>&1 &
daemon_pid=$!
for _ in $(seq 1 50); do
  if out=$("$cli" status -c "$work/daemon.yaml" --timeout 1 2>/dev/null) && [[ $out == IDLE* ]]; then
    break
  fi
  kill -0 "$daemon_pid" 2>/dev/null || { cat "$work/daemon.log"; exit 1; }
done
# Datagrams the kernel dropped because a receiver's socket buffer was full, per program (the
# sockets' drop counters of /proc/net/udp): a request or answer lost there no program saw.
udp_drops() {
  local line="" entry pid inode drops
  for entry in "selfcald:$daemon_pid" "arm:$arm_pid" "bench:$1"; do
    pid=${entry#*:}
    drops=0
    for inode in $(ls -l "/proc/$pid/fd" 2>/dev/null | sed -n 's/.*socket:\[\([0-9]*\)\].*/\1/p'); do
      drops=$((drops + $(awk -v i="$inode" '$10 == i { d += $13 } END { print d + 0 }' /proc/net/udp)))
    done
    line+="udp_drops_${entry%%:*}=$drops "
  done
  echo "$line"
}
rc=0
"$bench" -c "$work/daemon.yaml" --daemon-pid "$daemon_pid" --daemon-log "$work/daemon.log" \
  --seconds "$seconds" --rate "$rate" "$@" &
bench_pid=$!
# Counted every second while the bench runs (its socket goes with it), with the seconds since
# its start at which a count rose: drops at the 20 MiB request are not drops under the flood.
started=$SECONDS
drops="" rose=""
while kill -0 "$bench_pid" 2>/dev/null; do
  now=$(udp_drops "$bench_pid")
  [ -n "$drops" ] && [ "$now" != "$drops" ] && rose+="$((SECONDS - started)),"
  drops=$now
  sleep 1
done
wait "$bench_pid" || rc=$?
kill -0 "$daemon_pid" 2>/dev/null || { echo "BROKEN: selfcald died"; rc=1; }
echo "${drops}udp_drops_rose_at_s=${rose%,}"
# The sizes of the too-large requests the daemon logged in full (the first of each 10 s).
grep -o 'request too large: [0-9]* bytes' "$work/daemon.log" | sort | uniq -c | sed 's/^/# daemon log: /' || true
if [ $rc -ne 0 ]; then
  echo "--- daemon log (last 30 lines, cut at 300 characters)"
  tail -n 30 "$work/daemon.log" | cut -c1-300
  keep_work=1
fi
exit $rc
