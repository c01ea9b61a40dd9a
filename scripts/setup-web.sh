#!/usr/bin/env bash
# Installs what the dashboard's browser test needs on a fresh Debian 12 machine (idempotent):
# Debian's chromium (playwright drives it; `npx playwright install` is not used) and Node.js/npm from
# Debian when missing, then playwright-core from tests/dashboard/package-lock.json and web-ifc from
# tools/ifc/package-lock.json (npm ci).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
missing=()
command -v chromium >/dev/null 2>&1 || missing+=(chromium)
command -v node >/dev/null 2>&1 || missing+=(nodejs)
command -v npm >/dev/null 2>&1 || missing+=(npm)
# Fonts so the page renders text in screenshots.
dpkg-query -W -f='${Status}' fonts-dejavu-core 2>/dev/null | grep -q "install ok installed" || missing+=(fonts-dejavu-core)
if [ ${#missing[@]} -gt 0 ]; then
  echo "fploc setup-web: installing ${missing[*]}" >&2
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi
cd "$ROOT/tests/dashboard"
if [ ! -d node_modules/playwright-core ] || [ package-lock.json -nt node_modules/.package-lock.json ]; then
  echo "fploc setup-web: npm ci in tests/dashboard" >&2
  PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error >&2
fi
# web-ifc for reading IFC building models (tools/ifc/ifc2plan.mjs, used by modules/floorplan's .ifc reader).
cd "$ROOT/tools/ifc"
if [ ! -d node_modules/web-ifc ] || [ package-lock.json -nt node_modules/.package-lock.json ]; then
  echo "fploc setup-web: npm ci in tools/ifc" >&2
  npm ci --no-audit --no-fund --loglevel=error >&2
fi
# fploc import's MCAP tests: an independent MCAP writer (@mcap/core, @foxglove/cdr, zstd/lz4 codecs).
cd "$ROOT/tests/import"
if [ ! -d node_modules/@mcap/core ] || [ package-lock.json -nt node_modules/.package-lock.json ]; then
  echo "fploc setup-web: npm ci in tests/import" >&2
  npm ci --no-audit --no-fund --loglevel=error >&2
fi
