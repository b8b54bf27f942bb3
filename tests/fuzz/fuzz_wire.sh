#!/usr/bin/env bash
# Fuzzes the wire-format targets (tests/fuzz/fuzz_wire.cpp: pcap, vlp16_data, vlp16_position, raw_payloads,
# rig_datagram) without a full instrumented build: clang compiles just the core/wire sources they reach with
# libFuzzer, ASan and UBSan (libpcap itself is not instrumented). Usage, from the repository root:
#   bash tests/fuzz/fuzz_wire.sh TARGET SECONDS [WORKDIR]
# A crash leaves crash-<sha1> in WORKDIR (default /tmp/rotolidar_fuzz_TARGET); copy it into
# tests/fuzz/corpus/TARGET/ with the fix.
set -euo pipefail
target=${1:?target: pcap|vlp16_data|vlp16_position|raw_payloads|rig_datagram}
seconds=${2:?seconds}
work=${3:-/tmp/rotolidar_fuzz_$target}
mkdir -p "$work/corpus"
cp -n "tests/fuzz/corpus/$target/"* "$work/corpus/" 2>/dev/null || true
cat > "$work/main.cpp" <<'CPP'
#include <cstdlib>
#include "tests/fuzz/fuzz_target.hpp"
extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  static const rotolidar::fuzz::TargetFn target = rotolidar::fuzz::Registry().at(std::getenv("FUZZ_TARGET"));
  return target(data, size);
}
CPP
if [ ! -x "$work/fuzz_wire" ]; then
  clang++ -std=c++17 -O1 -g -fsanitize=fuzzer,address,undefined -I. -I/usr/include/eigen3 -I/usr/include/opencv4 \
    "$work/main.cpp" tests/fuzz/fuzz_wire.cpp core/wire/rig_protocol.cpp core/wire/packet_orderer.cpp \
    core/wire/vlp16.cpp core/wire/vlp16_decoder.cpp core/wire/packet_gaps.cpp core/wire/pcap.cpp core/types/calib.cpp \
    core/util/log.cpp \
    -lpcap -lopencv_core -o "$work/fuzz_wire"
fi
cd "$work"
FUZZ_TARGET=$target ./fuzz_wire corpus -max_total_time="$seconds" -rss_limit_mb=2048
