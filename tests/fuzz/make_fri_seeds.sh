#!/bin/sh
# Writes the seed corpus of fuzz_fri: FRI monitoring and command messages as a KUKA controller
# and our client send them, encoded from protocol-buffer text with protoc and protocols/fri/fri.proto.
# Usage: tests/fuzz/make_fri_seeds.sh [OUT_DIR]   (default tests/fuzz/seeds/fuzz_fri)
set -eu
root=$(cd "$(dirname "$0")/../.." && pwd)
out=${1:-$root/tests/fuzz/seeds/fuzz_fri}
mkdir -p "$out"
encode() {  # NAME MESSAGE_TYPE, the text on standard input
  protoc --proto_path="$root/protocols/fri" --encode="selfcal_fri.$2" fri.proto >"$out/$1.tmp"
  mv "$out/$1.tmp" "$out/$1.bin"
}
joints='value: 0.1 value: -0.2 value: 0.3 value: -0.4 value: 0.5 value: -0.6 value: 0.7'
encode monitoring-commanding FRIMonitoringMessage <<TEXT
header { messageIdentifier: 1 sequenceCounter: 42 reflectedSequenceCounter: 41 }
robotInfo { numberOfJoints: 7 safetyState: NORMAL_OPERATION driveState: ACTIVE driveState: ACTIVE
  driveState: ACTIVE driveState: ACTIVE driveState: ACTIVE driveState: ACTIVE driveState: ACTIVE
  operationMode: AUTOMATIC_MODE controlMode: POSITION_CONTROLMODE }
monitorData { measuredJointPosition { $joints } measuredTorque { $joints }
  commandedJointPosition { $joints } externalTorque { $joints }
  readIORequest { name: "Out1" type: DIGITAL direction: OUTPUT digitalValue: 1 }
  timestamp { sec: 1700000000 nanosec: 500000000 } }
connectionInfo { sessionState: COMMANDING_ACTIVE quality: EXCELLENT sendPeriod: 5 receiveMultiplier: 1 }
ipoData { jointPosition { $joints } clientCommandMode: POSITION overlayType: JOINT trackingPerformance: 1.0 }
requestedTransformations { name: "tool" matrix: 1 matrix: 0 matrix: 0 matrix: 0.1 timestamp { sec: 1 nanosec: 2 } }
endOfMessageData { messageLength: 0 messageChecksum { crc32: 0 } }
TEXT
encode monitoring-idle FRIMonitoringMessage <<TEXT
header { messageIdentifier: 1 sequenceCounter: 0 reflectedSequenceCounter: 0 }
connectionInfo { sessionState: IDLE quality: POOR }
TEXT
encode command-position FRICommandMessage <<TEXT
header { messageIdentifier: 2 sequenceCounter: 43 reflectedSequenceCounter: 42 }
commandData { jointPosition { $joints }
  writeIORequest { name: "Out1" type: ANALOG direction: OUTPUT analogValue: 0.25 } }
endOfMessageData { messageLength: 0 }
TEXT
encode command-empty FRICommandMessage <<TEXT
header { messageIdentifier: 2 sequenceCounter: 1 reflectedSequenceCounter: 0 }
TEXT
