#!/bin/bash
# selfcald as a process over udpm:// (run inside tests/netns-run), driven by the selfcal command
# line: refusal of a forged trigger, kill -9 while recording and while calibrating followed by a
# restart (a half-written model folder removed), a following trigger noticing a restart, a full accepted session, rollback, and a full disk (RLIMIT_FSIZE) during recording.
# The arm and sensor are the TestArm process; the engine is the scripted one (selfcald_scripted).
# Usage: daemon_process_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
source_dir=$1
build_dir=$2
selfcald=$build_dir/tests/daemon/selfcald_scripted
arm=$build_dir/tests/daemon/selfcal_test_arm
cli=$build_dir/tools/selfcal
work=$(mktemp -d /tmp/selfcal_daemon_process.XXXXXX)
url="udpm://239.255.76.67:7667?ttl=0"
daemon_pid=""
arm_pid=""

cleanup() {
  [ -n "$daemon_pid" ] && kill -9 "$daemon_pid" 2>/dev/null || true
  [ -n "$arm_pid" ] && kill "$arm_pid" 2>/dev/null || true
  wait 2>/dev/null || true
  if [ "${keep_work:-0}" = 1 ]; then echo "work folder kept: $work"; else rm -rf "$work"; fi
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*" >&2
  echo "--- daemon log (last 40 lines)" >&2
  tail -n 40 "$work/daemon.log" >&2 || true
  keep_work=1
  exit 1
}

cat >"$work/tiny.yaml" <<'PLAN'
name: tiny
scans:
  - {purpose: fit, from: [0.0, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0], to: [0.6, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0], speed: 0.3}
  - {purpose: fit, from: [0.6, 0.5, 0.0, -1.2, 0.0, 0.8, 0.0], to: [0.6, 0.5, 0.0, -1.2, 0.0, 0.8, 0.6], speed: 0.3}
  - {purpose: validation, from: [0.6, 0.4, 0.0, -1.2, 0.0, 0.8, 0.6], to: [0.6, 0.4, 0.0, -1.2, 0.6, 0.8, 0.6], speed: 0.3}
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
"$selfcald" --generate-key "$work/other.key" >/dev/null
cfg=(-c "$work/daemon.yaml")
nominal=$(cat "$source_dir/config/robots/kuka_lbr_iiwa_r840.yaml")

start_daemon() {  # ENGINE_SCRIPT [ulimit -f in KiB]
  if [ -n "${2:-}" ]; then
    (ulimit -f "$2"; SELFCAL_TEST_ENGINE=$1 exec "$selfcald" "${cfg[@]}") >>"$work/daemon.log" 2>&1 &
  else
    SELFCAL_TEST_ENGINE=$1 "$selfcald" "${cfg[@]}" >>"$work/daemon.log" 2>&1 &
  fi
  daemon_pid=$!
  for _ in $(seq 1 50); do
    if out=$("$cli" status "${cfg[@]}" --timeout 1 2>/dev/null) && [[ $out == IDLE* ]]; then return 0; fi
    kill -0 "$daemon_pid" 2>/dev/null || fail "selfcald exited at start"
  done
  fail "selfcald did not report IDLE"
}
wait_state() {  # STATE SECONDS
  local deadline=$((SECONDS + $2))
  while [ $SECONDS -lt $deadline ]; do
    out=$("$cli" status "${cfg[@]}" --timeout 1 2>/dev/null || true)
    [[ $out == "$1"* ]] && return 0
  done
  fail "state $1 not reached within $2 s (last: $out)"
}
current_model() { cat "$work/storage/models/current/model.yaml"; }
session_status() { grep '^status:' "$work/storage/sessions/$1/session.yaml" | awk '{print $2}'; }
latest_session() { ls "$work/storage/sessions" | sort | tail -n 1; }

"$arm" --lcm-url "$url" &
arm_pid=$!
start_daemon "seconds=1"
[ "$(current_model)" = "$nominal" ] || fail "the nominal model was not installed byte for byte"

echo "== a trigger signed with another key is refused"
if out=$("$cli" trigger "${cfg[@]}" --key "$work/other.key" 2>&1); then fail "forged trigger accepted: $out"; fi
[[ $out == *"wrong signature"* ]] || fail "forged trigger: $out"
grep -q "wrong signature" "$work/daemon.log" || fail "the refusal is not in the daemon's log"

echo "== kill -9 while recording, then restart"
"$cli" trigger "${cfg[@]}" --no-wait >/dev/null || fail "trigger refused"
wait_state RECORDING 20
session=$(latest_session)
kill -9 "$daemon_pid"; wait "$daemon_pid" 2>/dev/null || true
[ "$(session_status "$session")" = recording ] || fail "session.yaml should still say recording"
[ ! -e "$work/storage/sessions/$session/recording.lcmlog" ] || fail "an interrupted log looks complete"
[ -e "$work/storage/sessions/$session/recording.lcmlog.partial" ] || fail "no partial log"
start_daemon "seconds=30"
[ "$(session_status "$session")" = incomplete ] || fail "session not marked incomplete after restart"
[ "$(current_model)" = "$nominal" ] || fail "the current model changed"
"$cli" history "${cfg[@]}" | grep "$session" | grep -q incomplete || fail "history does not say incomplete"

echo "== kill -9 while calibrating, then restart"
"$cli" trigger "${cfg[@]}" --no-wait >/dev/null || fail "trigger refused"
wait_state CALIBRATING 40
session=$(latest_session)
[ -e "$work/storage/sessions/$session/recording.lcmlog" ] || fail "the recording was not committed before calibrating"
kill -9 "$daemon_pid"; wait "$daemon_pid" 2>/dev/null || true
# What a kill -9 during the install would have left of this session's model folder.
torn=$work/storage/models/$session
mkdir -p "$torn"
echo "<robot/>" >"$torn/model.urdf"
echo "joints: [" >"$torn/model.yaml.tmp.4242"
start_daemon "seconds=1,rms_before=0.01,rms_after=0.005,shift=0.004"
[ "$(session_status "$session")" = incomplete ] || fail "calibrating session not marked incomplete"
[ "$(current_model)" = "$nominal" ] || fail "the current model changed"
[ ! -e "$torn" ] || fail "the interrupted session's half-written model folder was left: $(ls "$torn")"

echo "== a trigger that follows its session notices a daemon restart within seconds"
"$cli" trigger "${cfg[@]}" >"$work/follow.out" 2>&1 &
follow_pid=$!
wait_state RECORDING 20
kill -9 "$daemon_pid"; wait "$daemon_pid" 2>/dev/null || true
killed_at=$SECONDS
start_daemon "seconds=1,rms_before=0.01,rms_after=0.005,shift=0.004"
if wait "$follow_pid"; then fail "trigger succeeded although selfcald lost its session: $(cat "$work/follow.out")"; fi
[ $((SECONDS - killed_at)) -le 10 ] || fail "trigger took $((SECONDS - killed_at)) s to notice"
grep -Eq "no longer knows session|no status from selfcald for" "$work/follow.out" ||
  fail "trigger does not say what happened: $(cat "$work/follow.out")"
echo "trigger after $((SECONDS - killed_at)) s: $(tail -n 1 "$work/follow.out")"

echo "== an accepted session, then rollback"
"$cli" trigger "${cfg[@]}" >"$work/trigger.out" 2>&1 || { cat "$work/trigger.out"; fail "session not accepted"; }
grep -q "ACCEPTED" "$work/trigger.out" || fail "trigger output lacks ACCEPTED"
grep -q "RECORDING" "$work/trigger.out" || fail "trigger output shows no progress"
session=$(latest_session)
[ "$(readlink "$work/storage/models/current")" = "$session" ] || fail "the new model is not current"
[ "$(current_model)" != "$nominal" ] || fail "the current model did not change"
grep -q "<robot" "$work/storage/models/$session/model.urdf" || fail "the accepted model has no URDF"
"$cli" history "${cfg[@]}" | grep "$session" | grep -q accepted || fail "history does not say accepted"
"$cli" rollback "${cfg[@]}" | grep -q "rolled back" || fail "rollback refused"
[ "$(current_model)" = "$nominal" ] || fail "rollback did not restore the nominal model"
if "$cli" rollback "${cfg[@]}" >/dev/null 2>&1; then
  # previous is now the session's model: a second rollback goes back to it.
  [ "$(readlink "$work/storage/models/current")" = "$session" ] || fail "second rollback"
  "$cli" rollback "${cfg[@]}" >/dev/null || fail "third rollback"
fi

echo "== a full disk during recording fails cleanly (RLIMIT_FSIZE 1 MiB)"
kill "$daemon_pid"; wait "$daemon_pid" 2>/dev/null || true
before=$(current_model)
start_daemon "seconds=1" 1024
if "$cli" trigger "${cfg[@]}" >"$work/trigger.out" 2>&1; then fail "a session on a full disk succeeded"; fi
grep -q "FAILED.*recording failed" "$work/trigger.out" || { cat "$work/trigger.out"; fail "no clear failure"; }
session=$(latest_session)
[ "$(session_status "$session")" = failed ] || fail "session not marked failed"
[ ! -e "$work/storage/sessions/$session/recording.lcmlog" ] || fail "a failed log looks complete"
[ "$(current_model)" = "$before" ] || fail "the current model changed"
kill -0 "$daemon_pid" || fail "the daemon died"
wait_state IDLE 5
echo "daemon_process_test: all passed"
