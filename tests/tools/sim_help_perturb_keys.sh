#!/usr/bin/env bash
# `fploc sim --help` names every --perturb key the parser takes (it listed 9 of 14: doors_moved, move_min, move_max,
# door_shift_min and door_shift_max were missing). The keys are taken from the parser's own error for an unknown key
# (sim::perturb_keys(), in its order); the help's "with the keys KEY: doc; KEY: doc; ..." list must be exactly that
# list, so a key added to the parser and not to the help, or one dropped from the help, fails here. (The test used to
# grep the help for each key as a word: "glass", "doors", "move", "add" are in the other keys' docs and other options'
# help, so a dropped key could still be found.)
set -euo pipefail
B="${FPLOC_BUILD_DIR:?run through ctest}/bin"
T="$(mktemp -d)"
trap 'rm -rf "$T"' EXIT
rc=0
"$B/fploc-sim" --scenario room-small-loop-medium --perturb wobble=1 --duration 1 --out "$T/x.lcm" --gt "$T/x.tum" 2> "$T/err" || rc=$?
[ "$rc" != 0 ] || { echo "--perturb wobble=1 accepted"; exit 1; }
keys=$(sed -n "s/.*unknown key 'wobble' (keys: \([^)]*\)).*/\1/p" "$T/err" | tr -d ' ')
[ -n "$keys" ] || { echo "no key list in the error:"; cat "$T/err"; exit 1; }
"$B/fploc-sim" --help > "$T/help" 2>&1
python3 - "$T/help" "$keys" <<'PY'
import re, sys
help_text, parser_keys = open(sys.argv[1]).read(), sys.argv[2].split(",")
# The --perturb option's description: from its flag to the next option's line (CLI11 wraps it over indented lines).
m = re.search(r"^\s*--perturb\b.*?(?=^\s*-)", help_text, re.S | re.M)
assert m, "no --perturb option in the help:\n" + help_text
desc = " ".join(m.group(0).split())
tail = desc.split("with the keys ", 1)
assert len(tail) == 2, "the --perturb help has no 'with the keys' list: " + desc
# "KEY: doc; KEY: doc; ...": each entry's name is what precedes its first ': '.
help_keys = [e.split(": ", 1)[0].strip() for e in tail[1].split("; ")]
assert len(parser_keys) >= 14, f"only {len(parser_keys)} keys in the parser's list: {parser_keys}"
assert help_keys == parser_keys, (f"--help lists the --perturb keys {help_keys},\nthe parser takes {parser_keys}\n"
                                  f"(missing from the help: {sorted(set(parser_keys) - set(help_keys))}, "
                                  f"not the parser's: {sorted(set(help_keys) - set(parser_keys))})")
print(f"sim --help: exactly the parser's {len(parser_keys)} --perturb keys, in its order")
PY
