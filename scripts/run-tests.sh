#!/usr/bin/env bash
# Runs every test of the project (unit tests, integration tests in network namespaces, browser tests).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${FPLOC_BUILD_DIR:-$ROOT/build}"
if [ ! -d "$ROOT/../shared/data" ]; then
  echo "note: ../shared/data not found beside the checkout; tests that need it will be skipped" >&2
fi
cd "$BUILD"
ctest -j "${FPLOC_TEST_JOBS:-2}" --output-on-failure --timeout 900 "$@"
