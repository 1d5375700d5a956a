#!/bin/sh
# Footprint of each driver (docs/performance.md "Driver footprint"): resident memory while it
# streams against its simulated peer for SECONDS, its stripped size and the shared libraries it
# loads. Every driver publishes over udpm:// inside a network namespace of its own
# (tests/netns-run), where lcm-logger records what it published, so a row counts real messages.
# Prints one line per driver: name, messages, rate, VmRSS and VmHWM (peak) at the end, size,
# libraries; then the markdown table rows.
# Usage: tests/bench/footprint/run_footprint.sh BUILD_DIR [SECONDS]   (default 10)
set -eu
source_dir=$(cd "$(dirname "$0")/../../.." && pwd)
if [ -z "${SELFCAL_FOOTPRINT_IN_NETNS:-}" ]; then
  SELFCAL_FOOTPRINT_IN_NETNS=1 exec "$source_dir/tests/netns-run" "$0" "$@"
fi
build=$(cd "$1" && pwd)
seconds=${2:-10}
url="udpm://239.255.76.67:7667?ttl=0"
work=$(mktemp -d)
pids=""
cleanup() {
  for pid in $pids; do kill "$pid" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT
rows=""

# Counts the events of an LCM log (sync word 0xEDA1DA01, 8-byte number and time, lengths).
count_events() {
  python3 - "$1" <<'EOF'
import os, struct, sys
size = os.path.getsize(sys.argv[1])
count = offset = 0
with open(sys.argv[1], "rb") as log:
    while offset + 28 <= size:
        log.seek(offset)
        sync, _, _, channel_length, data_length = struct.unpack(">IqqII", log.read(28))
        if sync != 0xEDA1DA01:
            break
        offset += 28 + channel_length + data_length
        count += 1 if offset <= size else 0
print(count)
EOF
}

# measure NAME BINARY PEER_DESCRIPTION -- DRIVER_COMMAND...: the peer runs already; starts the
# driver and lcm-logger, waits SECONDS, reads the driver's memory, stops both.
measure() {
  name=$1 binary=$2 peer=$3
  shift 4
  log=$work/$name.lcmlog
  # A receive buffer for whole depth clouds (megabytes), on the logger's side only.
  lcm-logger --lcm-url="$url&recv_buf_size=67108864" --quiet "$log" >/dev/null 2>&1 &
  logger=$!
  "$@" >"$work/$name.driver.log" 2>&1 &
  driver=$!
  pids="$pids $logger $driver"
  sleep "$seconds"
  if ! kill -0 "$driver" 2>/dev/null; then
    echo "error: $name exited early:" >&2
    tail -n 20 "$work/$name.driver.log" >&2
    exit 1
  fi
  rss_kb=$(awk '/^VmRSS:/ {print $2}' "/proc/$driver/status")
  hwm_kb=$(awk '/^VmHWM:/ {print $2}' "/proc/$driver/status")
  kill -INT "$driver" "$logger" 2>/dev/null || true
  wait "$driver" 2>/dev/null || true
  wait "$logger" 2>/dev/null || true
  messages=$(count_events "$log")
  rm -f "$log"
  strip -o "$work/stripped" "$binary"
  size_kb=$(($(stat -c %s "$work/stripped") / 1024))
  libraries=$(ldd "$binary" | grep -c '=>')
  needed=$(objdump -p "$binary" | awk '$1 == "NEEDED" {sub(/\.so.*/, "", $2); sub(/^lib/, "", $2); print $2}' |
    tr '\n' ' ' | sed 's/ $//')
  rate=$(awk -v m="$messages" -v s="$seconds" 'BEGIN {printf "%.1f", m / s}')
  echo "footprint: $name peer=\"$peer\" messages=$messages rate_hz=$rate vm_rss_kb=$rss_kb" \
    "vm_hwm_kb=$hwm_kb stripped_kb=$size_kb libraries=$libraries needed=\"$needed\""
  rows="$rows
| \`$(basename "$binary")\` | $peer | $messages ($rate/s) | $(awk -v k="$rss_kb" 'BEGIN {printf "%.1f", k / 1024}') MB | **$(awk -v k="$hwm_kb" 'BEGIN {printf "%.1f", k / 1024}') MB** | $size_kb KB | $libraries | $needed |"
}

start_peer() {  # start_peer LOG COMMAND...: runs a simulated device in the background
  peer_log=$1
  shift
  "$@" >"$peer_log" 2>&1 &
  pids="$pids $!"
}

# Hokuyo: selfcal-sim-scip on a pseudo-terminal (its serial line), the driver on that device.
start_peer "$work/scip.log" "$build/tools/sim_scip/selfcal-sim-scip" --pty --link "$work/ttyHokuyo"
for _ in $(seq 50); do [ -e "$work/ttyHokuyo" ] && break; sleep 0.1; done
measure hokuyo "$build/drivers/hokuyo/selfcal-hokuyo" "selfcal-sim-scip, pty" -- \
  "$build/drivers/hokuyo/selfcal-hokuyo" --device "$work/ttyHokuyo" --lcm-url "$url"

# FRI: selfcal-sim-fri (the KUKA controller, 5 ms period) and the FRI client on UDP 127.0.0.1.
model=$source_dir/config/robots/kuka_lbr_iiwa_r840.yaml
start_peer "$work/fri.log" "$build/tools/sim_fri/selfcal-sim-fri" --model "$model" --client-port 30210
measure iiwa "$build/drivers/iiwa/selfcal-iiwa" "selfcal-sim-fri, UDP" -- \
  "$build/drivers/iiwa/selfcal-iiwa" --model "$model" --fri-port 30210 --lcm-url "$url"

# CANopen: the driver produces SYNC every 5 ms; cansend plays two drives' TPDOs as fast as a
# shell loop runs, all through the SocketCAN preload shim (this kernel has no AF_CAN).
cat >"$work/arm.yaml" <<'EOF'
interface: vcan0
sync: {produce: true, period: 0.005}
start_nodes: false
heartbeat_timeout: 30
joints:
  - {name: J1, node: 1, pdo: 1, position_offset: 2, counts_per_revolution: 65536}
  - {name: J2, node: 2, pdo: 1, position_offset: 2, counts_per_revolution: 65536}
EOF
export SELFCAL_CANSHIM_INTERFACES=vcan0
shim=$build/drivers/canopen/libselfcal_canshim.so
LD_PRELOAD=$shim sh -c 'while :; do cansend vcan0 181#3706E8030000; cansend vcan0 182#370600F0FFFF; done' \
  >"$work/cansend.log" 2>&1 &
pids="$pids $!"
measure canopen "$build/drivers/canopen/selfcal-canopen" "cansend (2 drives), preload shim" -- \
  env LD_PRELOAD="$shim" "$build/drivers/canopen/selfcal-canopen" --config "$work/arm.yaml" --lcm-url "$url"
unset SELFCAL_CANSHIM_INTERFACES

# Wenglor: the fake libEthernetScanner.so (tools/sim_wenglor) at the shipped 500 Hz line rate.
measure wenglor "$build/drivers/wenglor/selfcal-wenglor" "fake libEthernetScanner.so, 500 Hz" -- \
  "$build/drivers/wenglor/selfcal-wenglor" --config "$source_dir/config/drivers/wenglor.yaml" \
  --library "$build/tools/sim_wenglor/libEthernetScanner.so" --ip 127.0.0.1 --lcm-url "$url"

# Aravis: the fake GigE Vision camera (PhotoNeo-like, 1120 x 800, 20 Hz) on 127.0.0.1, free run.
start_peer "$work/gev.log" "$build/tools/sim_cameras/selfcal-fake-gev-camera" --address 127.0.0.1
sleep 1
measure aravis "$build/drivers/aravis/selfcal-aravis" "fake GigE camera 1120 x 800, 20 Hz" -- \
  "$build/drivers/aravis/selfcal-aravis" --address 127.0.0.1 --trigger free-run --lcm-url "$url"
# The same with the fewest stream buffers the driver accepts (each holds a whole frame).
measure aravis-2-buffers "$build/drivers/aravis/selfcal-aravis" "same, --buffers 2" -- \
  "$build/drivers/aravis/selfcal-aravis" --address 127.0.0.1 --trigger free-run --buffers 2 \
  --lcm-url "$url"
# A UDP socket instead of Aravis' packet socket, whose ring is resident (32 MiB).
measure aravis-standard-socket "$build/drivers/aravis/selfcal-aravis" "same, --stream-socket standard" -- \
  "$build/drivers/aravis/selfcal-aravis" --address 127.0.0.1 --trigger free-run \
  --stream-socket standard --lcm-url "$url"

# OpenNI2: the real libOpenNI2 loading our simulated camera from a private driver folder,
# Kinect Azure NFOV size (640 x 576) at 30 Hz.
openni2_library=$(ldd "$build/drivers/openni2/selfcal-openni2" | awk '/libOpenNI2/ {print $3}')
mkdir -p "$work/openni2/OpenNI2/Drivers"
ln -s "$(readlink -f "$openni2_library")" "$work/openni2/libOpenNI2.so.0"
cp "$build/tools/sim_cameras/libselfcal-sim-openni2.so.0" "$work/openni2/OpenNI2/Drivers/"
measure openni2 "$build/drivers/openni2/selfcal-openni2" "OpenNI2 plugin 640 x 576, 30 Hz" -- \
  env LD_LIBRARY_PATH="$work/openni2" "$build/drivers/openni2/selfcal-openni2" \
  --uri "selfcal-sim://depth?width=640&height=576&fps=30&hfov_deg=75&vfov_deg=65" --lcm-url "$url"

echo
echo "| driver | peer | messages in ${seconds} s | VmRSS at the end | VmHWM (peak) | stripped size | shared libraries (ldd) | linked directly (NEEDED) |"
echo "|---|---|---|---|---|---|---|---|"
echo "$rows" | sed '/^$/d'
