#!/usr/bin/env bash
# Builds and runs the test suite under sanitizers, in their own build folders:
#   scripts/sanitize.sh [asan]  AddressSanitizer + UndefinedBehaviorSanitizer, all tests
#                               (build-asan/; about 6 min on 2 cores, build included)
#   scripts/sanitize.sh tsan    ThreadSanitizer, all tests (build-tsan/). TSan must see
#                               oneTBB's synchronisation, so this first builds Debian's own
#                               oneTBB source (apt-get source onetbb, the libtbb-dev version)
#                               with TBB_SANITIZE=thread and links the tests against it
#                               (about 11 min on 2 cores: 2.5 for TBB, once). GDAL stays
#                               uninstrumented: scripts/tsan.supp says what that hides.
# Needs what scripts/setup.sh installs. Any sanitizer report fails the run (exit 1).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
mode=${1:-asan}
jobs=${JOBS:-2}
# note: no dpts-mpi: Open MPI is not instrumented (its own leaks and races would be reported).
# Nor the Python module or the installed-package test: an instrumented library cannot be
# loaded into an uninstrumented python3 or consumer (the sanitizer runtime must come first).
common=(-G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DDPTS_BUILD_BENCH=OFF -DDPTS_BUILD_MPI=OFF
        -DDPTS_BUILD_PYTHON=OFF -DDPTS_TEST_PACKAGE=OFF)

run_asan() {
  cmake -S "$root" -B "$root/build-asan" "${common[@]}" \
    -DCMAKE_CXX_FLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all"
  ninja -C "$root/build-asan" -j "$jobs"
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir "$root/build-asan" -j "$jobs" --output-on-failure
}

# Debian's oneTBB source, built with -fsanitize=thread into build-tsan/tbb (once).
tsan_tbb() {
  local prefix=$root/build-tsan/tbb
  [ -e "$prefix/lib/cmake/TBB/TBBConfig.cmake" ] && return
  local src=$root/build-tsan/tbb-src
  mkdir -p "$src"
  if ! ls "$src"/onetbb_*.orig.tar.* >/dev/null 2>&1; then
    if ! grep -rqs "^deb-src" /etc/apt/sources.list /etc/apt/sources.list.d/; then
      local sudo_cmd; sudo_cmd=$([ "$(id -u)" = 0 ] && echo "" || echo sudo)
      echo "deb-src [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] http://deb.debian.org/debian bookworm main" |
        $sudo_cmd tee /etc/apt/sources.list.d/dpts-src.list >/dev/null
      $sudo_cmd apt-get update -q >/dev/null
    fi
    (cd "$src" && apt-get source --download-only onetbb >/dev/null)
  fi
  tar -C "$src" -xf "$src"/onetbb_*.orig.tar.*
  cmake -S "$src"/oneTBB-* -B "$src/build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DTBB_SANITIZE=thread -DTBB_TEST=OFF -DTBB_EXAMPLES=OFF -DTBB_STRICT=OFF \
    -DCMAKE_INSTALL_PREFIX="$prefix" >/dev/null
  ninja -C "$src/build" -j "$jobs" install >/dev/null
}

run_tsan() {
  tsan_tbb
  cmake -S "$root" -B "$root/build-tsan" "${common[@]}" -DTBB_DIR="$root/build-tsan/tbb/lib/cmake/TBB" \
    -DCMAKE_CXX_FLAGS="-fsanitize=thread -fno-omit-frame-pointer"
  ninja -C "$root/build-tsan" -j "$jobs"
  LD_LIBRARY_PATH="$root/build-tsan/tbb/lib" \
    TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$root/scripts/tsan.supp" \
    ctest --test-dir "$root/build-tsan" -j "$jobs" --output-on-failure
}

case "$mode" in
  asan) run_asan ;;
  tsan) run_tsan ;;
  *) echo "usage: scripts/sanitize.sh [asan|tsan]" >&2; exit 2 ;;
esac
