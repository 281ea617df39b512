#!/usr/bin/env bash
# Installs what is missing, builds (Release) and runs the whole test suite with ctest.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$here/tools/setup.sh"
build="${SPHFSI_BUILD_DIR:-$here/build}"
cd "$build"
ctest --output-on-failure -j"$(nproc)" "$@"
