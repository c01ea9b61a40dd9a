# Sourced by the shell tests of `fploc import` (tests/import/*.sh). Needs I (the importer) and T (a scratch folder).
#   fail TEXT                     counts a failure (fails) and prints it
#   run NAME EXPECTED_RC ARGS...  runs the importer: stdout -> $T/NAME.out, stderr -> $T/NAME.err; a wrong exit fails
#   err NAME TEXT                 stderr of NAME is exactly one line holding TEXT
#   jcheck NAME PYTHON_EXPR       $T/NAME.out is a JSON document and the expression over j holds
fails=0
fail() { echo "FAIL: $*"; fails=$((fails + 1)); }
run() {
  local name="$1" want="$2"; shift 2
  "$I" "$@" > "$T/$name.out" 2> "$T/$name.err"; local rc=$?
  [ "$rc" = "$want" ] || { fail "$name: exit $rc, expected $want"; sed 's/^/    /' "$T/$name.err" | head -5; }
}
err() {
  [ "$(wc -l < "$T/$1.err")" = 1 ] || fail "$1: $(wc -l < "$T/$1.err") stderr lines, expected 1"
  grep -qF -- "$2" "$T/$1.err" || { fail "$1: stderr lacks '$2'"; sed 's/^/    /' "$T/$1.err"; }
}
jcheck() {
  python3 - "$T/$1.out" "$2" 2>/dev/null <<'PY' || fail "$1: $2"
import json, sys
j = json.load(open(sys.argv[1], encoding="utf-8"))
sys.exit(0 if eval(sys.argv[2]) else 1)
PY
}
