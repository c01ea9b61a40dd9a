#!/usr/bin/env bash
# Runs browser_test.mjs (playwright-core + Debian's chromium). Skips (exit 77) when either is missing.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
CHROMIUM="${FPLOC_CHROMIUM:-/usr/bin/chromium}"
if [ ! -x "$CHROMIUM" ]; then
  echo "SKIP: $CHROMIUM not found; run scripts/setup-web.sh (installs Debian's chromium and playwright-core)" >&2
  exit 77
fi
if ! command -v node >/dev/null 2>&1; then
  echo "SKIP: node not found; run scripts/setup-web.sh" >&2
  exit 77
fi
if [ ! -d "$HERE/node_modules/playwright-core" ]; then
  echo "SKIP: $HERE/node_modules/playwright-core missing; run scripts/setup-web.sh (npm ci there)" >&2
  exit 77
fi
exec node "$HERE/browser_test.mjs" "$@"
