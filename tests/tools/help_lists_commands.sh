#!/usr/bin/env bash
# `fploc help` names every command that README.md says it lists ("`bin/fploc help` lists the commands (...)"),
# subcommands included (map compare/diff, import-carmen and occupancy were missing), each with a built executable.
# bin/fploc runs with FPLOC_SKIP_BUILD=1: the built programs as they are (`fploc bench` ran `cmake --build` on the
# build directory from inside ctest). A `cmake` first in PATH records any call: there must be none.
set -euo pipefail
R="${FPLOC_ROOT:?run through ctest}"
B="${FPLOC_BUILD_DIR:?run through ctest}/bin"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
H="$T/help"
mkdir "$T/fakebin"
printf '#!/bin/sh\necho "cmake $*" >> "%s/cmake-called"\n' "$T" > "$T/fakebin/cmake"
chmod +x "$T/fakebin/cmake"
fploc() { PATH="$T/fakebin:$PATH" FPLOC_SKIP_SETUP=1 FPLOC_SKIP_BUILD=1 "$R/bin/fploc" "$@"; }
fploc help 2> "$H"  # the usage goes to stderr
python3 - "$R/README.md" "$H" "$B" <<'PY'
import os, re, sys
readme, help_text, bindir = open(sys.argv[1]).read(), open(sys.argv[2]).read(), sys.argv[3]
m = re.search(r"`bin/fploc help` lists the commands \(([^)]*)\)", readme)
assert m, "README.md: no '`bin/fploc help` lists the commands (...)'"
lines = [l.strip() for l in help_text.splitlines()]
bad = []
for item in (x.strip() for x in m.group(1).replace("\n", " ").split(",")):
    words = item.split()
    cmd, subs = words[0], (words[1].split("/") if len(words) > 1 else [])
    line = next((l for l in lines if l.split(" ", 1)[0] == cmd), None)
    if line is None:
        bad.append(f"'{cmd}' not in fploc help")
        continue
    named = set(re.split(r"[\s|]+", line.split("  ")[0]))
    for s in subs:
        if s not in named:
            bad.append(f"'{cmd} {s}' not on help's line '{line}'")
        exe = f"fploc-{cmd}-{s}"
        if not (os.path.exists(os.path.join(bindir, exe)) or os.path.exists(os.path.join(bindir, f"fploc-{cmd}"))):
            bad.append(f"no {exe} or fploc-{cmd} in {bindir}")
    if not subs and not os.path.exists(os.path.join(bindir, f"fploc-{cmd}")):
        bad.append(f"no fploc-{cmd} in {bindir}")
for b in bad:
    print("FAIL:", b)
sys.exit(1 if bad else 0)
PY
# A command of two words without its second (`fploc bench`, `fploc bench --help`) lists the second words; `fploc map
# --help` names `diff` (its own program). Both said "unknown command" / left diff out.
out="$(fploc bench --help 2>&1)" || { echo "FAIL: fploc bench --help: exit $?: $out"; exit 1; }
echo "$out" | grep -q "^usage: fploc bench <.*paper.*realism.*>" || { echo "FAIL: fploc bench --help: $out"; exit 1; }
out="$(fploc bench nosuch 2>&1)" && { echo "FAIL: fploc bench nosuch: exit 0"; exit 1; }
echo "$out" | grep -q "unknown command 'bench nosuch' (fploc bench: one of .*paper" || { echo "FAIL: fploc bench nosuch: $out"; exit 1; }
fploc map --help | grep -q "diff (plan changes seen in a recorded run" || { echo "FAIL: fploc map --help does not name diff"; exit 1; }
"$B/fploc-map" --help | grep -q "diff (plan changes seen in a recorded run" || { echo "FAIL: fploc-map --help does not name diff"; exit 1; }
if [ -e "$T/cmake-called" ]; then echo "FAIL: bin/fploc ran a build inside the test: $(cat "$T/cmake-called")"; exit 1; fi
echo OK
