#!/usr/bin/env bash
# Builds (via setup.sh) and runs the whole test suite, then the same suite under
# AddressSanitizer + UndefinedBehaviorSanitizer and under ThreadSanitizer (scripts/sanitize.sh;
# 15-20 minutes in all from a fresh clone on 2 cores, well inside CI's 90).
# DPTS_SANITIZE=0 skips the sanitizer builds, for a quick local run. The exit status is the
# first failure's.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/scripts/setup.sh"
(cd "$root/build" && ctest --output-on-failure -j 2)
if [ "${DPTS_SANITIZE:-1}" != 0 ]; then
  "$root/scripts/sanitize.sh" asan
  "$root/scripts/sanitize.sh" tsan
fi
