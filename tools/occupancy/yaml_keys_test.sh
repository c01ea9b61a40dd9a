#!/bin/sh
# A map_server YAML with a misspelt key: one warning naming file, line and key (ROS ignores unknown keys, so
# the map still loads, exit 0); a required key missing: one error naming it, exit 1. The misspelt key was
# silently ignored (occupied_thresh then the default 0.65).
MAP="$1"; OCC="$2"; PLAN="$3"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; cat "$T/err"; exit 1; }
"$MAP" export-pgm --plan "$PLAN" --resolution 0.05 --out "$T/m" 2>/dev/null || fail "export-pgm"
sed 's/^occupied_thresh:/ocupied_thresh:/' "$T/m/map.yaml" > "$T/m/typo.yaml"
line=$(grep -n '^ocupied_thresh' "$T/m/typo.yaml" | cut -d: -f1)
[ -n "$line" ] || fail "no occupied_thresh line in the exported map.yaml"
"$OCC" "$T/m/typo.yaml" > /dev/null 2> "$T/err" || fail "a misspelt key made the map fail"
grep -qF "warning: $T/m/typo.yaml: line $line: unknown key 'ocupied_thresh' (ignored, as map_server does; did you mean 'occupied_thresh'?)" "$T/err" ||
  fail "no warning naming file, line $line and the key"
[ "$(grep -c warning "$T/err")" = 1 ] || fail "not exactly one warning"
grep -v '^resolution:' "$T/m/map.yaml" > "$T/m/nores.yaml"
"$OCC" "$T/m/nores.yaml" > /dev/null 2> "$T/err" && fail "a missing resolution was accepted"
[ "$(grep -c . "$T/err")" = 1 ] || fail "not exactly one error line"
grep -qF "$T/m/nores.yaml: resolution: missing" "$T/err" || fail "the error does not name the file and the key"
# An all-free map: one error naming the YAML and its own occupied_thresh, exit 1 (it was exit 0 with "0 boundary cells
# -> 0 segments", while replay said "occupied_thresh 0.995000", a threshold the YAML does not have).
printf 'P5\n8 8\n255\n' > "$T/m/free.pgm"; head -c 64 /dev/zero | tr '\0' '\376' >> "$T/m/free.pgm"
sed 's/^image:.*/image: free.pgm/' "$T/m/map.yaml" > "$T/m/free.yaml"
"$OCC" "$T/m/free.yaml" > /dev/null 2> "$T/err" && fail "an all-free map was accepted"
[ "$(grep -c . "$T/err")" = 1 ] || fail "not exactly one error line"
grep -qF "$T/m/free.yaml: image: no occupied cells (no pixel above occupied_thresh 0.65 of the YAML)" "$T/err" ||
  fail "the error does not name the file and the YAML's occupied_thresh"
echo OK
