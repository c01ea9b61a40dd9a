#!/bin/sh
# fploc import-carmen's number options given nan or inf: one error naming the option, exit 1, nothing written
# (CLI11's Range/PositiveNumber checks let NaN through: --resolution nan wrote a map.yaml saying "resolution: nan").
set -e
IMP="$1"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
for k in 0 1 2 3 4 5 6 7; do
  printf 'ODOM %s 0 0 0 0 0 %s.0 h %s.0\nFLASER 4 1.0 2.0 3.0 2.5 %s 0 0 %s 0 0 %s.5 h %s.5\n' "0.$k" "$k" "$k" "0.$k" "0.$k" "$k" "$k"
done > "$T/a.log"
"$IMP" "$T/a.log" --out "$T/ok.lcm" 2>/dev/null || fail "good log"
for bad in "--resolution nan" "--begin nan" "--coverage-radius nan"; do
  set -- $bad
  if "$IMP" "$T/a.log" --out "$T/n.lcm" --map "$T/m" $bad 2> "$T/err"; then fail "$bad accepted"; fi
  grep -qx "fploc import-carmen: $1 $2: not a finite number" "$T/err" || { cat "$T/err"; fail "$bad: error text"; }
  [ ! -e "$T/n.lcm" ] && [ ! -e "$T/m" ] || fail "$bad: wrote output"
done
# The map's defaults are those of `fploc bench real` (1 hit, 10 %, 0.1 m clearance; 2 / 25 % / 0 erased walls grazed
# by beams), reported in the JSON; --help shows the default of every option that has one.
"$IMP" "$T/a.log" --out "$T/d.lcm" --map "$T/dm" --map-end 1 --json > "$T/d.json" 2>/dev/null || fail "default map"
for kv in '"min_hits": 1' '"occupied_ratio": 0.1' '"hit_clearance_m": 0.1'; do
  grep -Eq "$kv,?\$" "$T/d.json" || { cat "$T/d.json"; fail "default map: no $kv in the JSON"; }
done
"$IMP" --help > "$T/help" 2>&1 || fail "--help"
for od in "--min-hits:1" "--occupied-ratio:0.1" "--hit-clearance:0.1" "--resolution:0.05" "--map-end:0.5" "--split-covered-share:0.75" \
          "--odom-from:odom" "--refine-method:lines" "--coverage-radius:0.1"; do
  o=${od%%:*} d=${od#*:}
  grep -E -- "^ +$o [A-Z].*=$d( |$)" "$T/help" > /dev/null || { cat "$T/help"; fail "--help: $o does not show its default $d"; }
done
# --begin/--end selecting no scans say the range; with --auto-split, the split (bench real --end 0.6 on aces, whose
# split is 0.65, said only "--begin/--end select no scans").
if "$IMP" "$T/a.log" --auto-split --end 0.1 --out "$T/s.lcm" 2> "$T/err"; then fail "--end below the split accepted"; fi
grep -q "^fploc import-carmen: --end 0.1 selects no scans: the automatic split (--auto-split) is at 0.625 (scan 5 of 8), .*(scan 1)" "$T/err" \
  || { cat "$T/err"; fail "--end below the split: error text"; }
if "$IMP" "$T/a.log" --begin 0.5 --end 0.5 --out "$T/s.lcm" 2> "$T/err"; then fail "--begin = --end accepted"; fi
grep -qx "fploc import-carmen: --begin 0.5 / --end 0.5 select no scans (scans 4..4 of 8)" "$T/err" || { cat "$T/err"; fail "--begin = --end: error text"; }
# --refine-map-poses: the map's scans refined before rasterising, reported under map.refine (passes run, poses kept when
# the scans do not constrain them, as these four-beam ones do not).
"$IMP" "$T/a.log" --out "$T/r.lcm" --map "$T/rm" --map-end 1 --refine-map-poses 2 --map-poses-out "$T/poses.txt" --json > "$T/r.json" 2>/dev/null \
  || fail "--refine-map-poses"
grep -q '"refine"' "$T/r.json" || fail "--refine-map-poses: no map.refine in the JSON"
[ "$(grep -vc '^#' "$T/poses.txt")" = 8 ] || fail "--map-poses-out: not 8 poses"
# A log damaged part way (a bad record, a .gz cut short): the scans before the damage are written (log and --tum), then
# one error naming the place, exit 1.
{ cat "$T/a.log"; echo "FLASER 4 1.0"; cat "$T/a.log"; } > "$T/bad.log"
if "$IMP" "$T/bad.log" --out "$T/b.lcm" --tum "$T/b.tum" 2> "$T/err"; then fail "bad record accepted"; fi
grep -q "bad.log:17: FLASER: 3 fields, expected at least 13 for 4 readings (the log ends there: 8 scans read before it, scans 0..8 of them written)" "$T/err" \
  || { cat "$T/err"; fail "bad record: error text"; }
[ "$(grep -vc '^#' "$T/b.tum")" = 8 ] && [ -s "$T/b.lcm" ] || fail "bad record: the 8 scans before it not written"
"$IMP" "$T/bad.log" --out "$T/b2.lcm" --json > "$T/b.json" 2>/dev/null && fail "bad record accepted (--json)"
grep -q '"damage": "[^"]*bad.log:17: FLASER' "$T/b.json" || { cat "$T/b.json"; fail "bad record: no \"damage\" in the JSON"; }
for k in $(seq 1 40); do cat "$T/a.log"; done > "$T/long.log"
gzip -c "$T/long.log" > "$T/long.log.gz"
head -c $(( $(wc -c < "$T/long.log.gz") / 2 )) "$T/long.log.gz" > "$T/cut.log.gz"
if "$IMP" "$T/cut.log.gz" --out "$T/c.lcm" --tum "$T/c.tum" 2> "$T/err"; then fail "cut .gz accepted"; fi
grep -q "cut.log.gz: compressed data end early after .* B decompressed (file truncated?) (the log ends there: .* scans read before it" "$T/err" \
  || { cat "$T/err"; fail "cut .gz: error text"; }
n=$(grep -vc '^#' "$T/c.tum")
[ "$n" -gt 0 ] && [ "$n" -lt 320 ] && [ -s "$T/c.lcm" ] || fail "cut .gz: $n scans written"
echo OK
