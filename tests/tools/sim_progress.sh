#!/usr/bin/env bash
# `fploc sim --duration S` counts its progress against the frames it writes: with --duration 60 on a 600 s path it
# printed "frame 100/6015 ... frame 600/6015" and then "wrote 600 scans".
set -euo pipefail
B="${FPLOC_BUILD_DIR:?run through ctest}/bin"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
"$B/fploc-sim" --scenario room-small-loop-fast --no-clutter --beams os1-32 --duration 20 --out "$T/x.lcm" --gt "$T/x.tum" 2> "$T/err" ||
  { cat "$T/err"; exit 1; }
grep -q "wrote 200 scans" "$T/err" || { cat "$T/err"; echo "FAIL: not 200 scans"; exit 1; }
tr '\r' '\n' < "$T/err" | grep -q "^  frame 200/200$" || { cat "$T/err"; echo "FAIL: progress not counted against the 200 frames written"; exit 1; }
echo OK
