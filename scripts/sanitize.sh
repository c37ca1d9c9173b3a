#!/usr/bin/env bash
# Builds and runs the test suite under sanitizers, in their own build folders:
#   scripts/sanitize.sh [asan]  AddressSanitizer + UndefinedBehaviorSanitizer, all tests
#                               (build-asan/; about 4.5 min on 2 cores, build included)
#   scripts/sanitize.sh tsan    ThreadSanitizer, the parallel and determinism tests
#                               (build-tsan/). Not clean yet: Debian's oneTBB is not built with
#                               -fsanitize=thread, so TSan cannot see the synchronisation of
#                               its task joins and reports races on data handed across a
#                               parallel_for (scripts/tsan.supp covers TBB's own frames and
#                               GDAL's internal lock order). It needs an instrumented oneTBB.
# Needs what scripts/setup.sh installs. Any sanitizer report fails the run (exit 1).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
mode=${1:-asan}
jobs=${JOBS:-2}
common=(-G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DDPTS_BUILD_BENCH=OFF)

run_asan() {
  cmake -S "$root" -B "$root/build-asan" "${common[@]}" \
    -DCMAKE_CXX_FLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all"
  ninja -C "$root/build-asan" -j "$jobs"
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir "$root/build-asan" -j "$jobs" --output-on-failure
}

run_tsan() {
  cmake -S "$root" -B "$root/build-tsan" "${common[@]}" \
    -DCMAKE_CXX_FLAGS="-fsanitize=thread -fno-omit-frame-pointer"
  ninja -C "$root/build-tsan" -j "$jobs"
  TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$root/scripts/tsan.supp" \
    ctest --test-dir "$root/build-tsan" -j "$jobs" --output-on-failure \
    -R "thread|determinism|meta|VP'|pieces|parallel"
}

case "$mode" in
  asan) run_asan ;;
  tsan) run_tsan ;;
  *) echo "usage: scripts/sanitize.sh [asan|tsan]" >&2; exit 2 ;;
esac
