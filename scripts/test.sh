#!/usr/bin/env bash
# Builds (via setup.sh) and runs the whole test suite; the exit status is ctest's.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/scripts/setup.sh"
cd "$root/build"
ctest --output-on-failure -j 2
