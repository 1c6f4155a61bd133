#!/usr/bin/env bash
# Installs, builds and runs the test suite (GoogleTest through CTest; OpenCL
# kernels run on the PoCL CPU device).
#
#   scripts/test.sh [ctest args...]              the whole suite, in build/;
#       under CI (CI=true, no ctest args) the same tests as --opencl and
#       --sanitize, side by side: each test runs once, each test file
#       compiles once
#   scripts/test.sh --opencl [ctest args...]     only the tests that need an
#       OpenCL device (label `opencl`), in build/
#   scripts/test.sh --sanitize [ctest args...]   AddressSanitizer + UBSan build
#       in build-sanitize/ (clang; -O2, -O0 for the test files and the
#       stages the host tests only pass through, unity batches; host/ and
#       tests/CMakeLists.txt) of the tests that need no OpenCL device
#       (label `host`, see tests/CMakeLists.txt); any report fails its test.
#
# Labels: host/opencl (needs a device or not), fast/e2e (e.g. `-L fast`).
# The suite needs an OpenCL device: without one, test.sh stops at once, and a
# device test fails rather than skips (SAPMVS_REQUIRE_OPENCL=1). Without a
# driver, run the host tests: SAPMVS_REQUIRE_OPENCL=0 scripts/test.sh -L host.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
# install-deps.sh installs Chromium: the tests that open report.html in it
# fail without it rather than skip.
export SAPMVS_REQUIRE_BROWSER="${SAPMVS_REQUIRE_BROWSER:-1}"
if [ "${CI:-}" = "true" ] && [ $# -eq 0 ]; then
  bash scripts/install-deps.sh
  export SAPMVS_DEPS_INSTALLED=1
  # The two stages run side by side, each line marked with its stage. One
  # after the other they took 14.9 min on 2 cores for about 1,320 CPU
  # seconds, 1.5 cores busy on average: each stage's configure, links and
  # tests left a core idle. Side by side: 11.3 min, the cores 4 % idle. The
  # device stage yields (nice): the sanitizer stage is the longer one, and
  # what it leaves idle the device stage takes.
  logs=$(mktemp -d)
  # Both builds render the same simulated blocks byte for byte: the first
  # stage to need one renders it for both (tests/test_util.h).
  export SAPMVS_SIM_CACHE="${SAPMVS_SIM_CACHE:-$logs/sim}"
  ( bash "$0" --sanitize 2>&1 | tee "$logs/sanitize" | sed -u 's/^/[sanitize] /' ) &
  sanitize=$!
  status=0
  ( nice -n 10 bash "$0" --opencl 2>&1 | tee "$logs/opencl" | sed -u 's/^/[opencl] /' ) || status=$?
  wait "$sanitize" || status=$?
  # CTest's closing lines once more, unmarked, as a log reader expects them.
  grep -h -E "tests passed|tests failed out of" "$logs/opencl" "$logs/sanitize" || true
  rm -rf "$logs"
  exit "$status"
fi
if [ "${1:-}" = "--sanitize" ]; then
  shift
  [ -n "${SAPMVS_DEPS_INSTALLED:-}" ] || bash scripts/install-deps.sh
  build=build-sanitize
  start=$(date +%s)
  if [ ! -f "$build/CMakeCache.txt" ]; then
    launcher=()
    command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
    # Line tables only: reports still have file:line stacks. No NDEBUG, so
    # that assertions are checked too. clang, where build/ is gcc's: the
    # code is checked by both compilers (clang found a scene that depended
    # on gcc's order of evaluating arguments), and clang compiled this build
    # in 440 CPU seconds against gcc's 630 at -O1. -O2: as quick to compile
    # with clang as -O1 (449 CPU seconds), and the tests ran in 277 against
    # 330, since clang's -O1 leaves Eigen's small products out of line.
    # float-cast-overflow is named so that the flags also hold for gcc.
    san="-fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all"
    cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Sanitize -DCMAKE_CXX_COMPILER=clang++ \
      -DCMAKE_CXX_FLAGS_SANITIZE="-O2 -g1 -fno-omit-frame-pointer $san" \
      -DCMAKE_EXE_LINKER_FLAGS_SANITIZE="-fsanitize=address,undefined,float-cast-overflow" \
      -DSAPMVS_BUILD_BENCHMARKS=OFF -DSAPMVS_TESTS_HOST_ONLY=ON -DSAPMVS_UNITY_BUILD=ON \
      "${launcher[@]}" >/dev/null
  fi
  cmake --build "$build" --target sapmvs_tests -j"$jobs"
  built=$(date +%s)
  export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
  export LSAN_OPTIONS="suppressions=$PWD/tests/sanitize/lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS}"
  ctest --test-dir "$build" --output-on-failure -L host -j"$jobs" "$@"
  echo "test.sh --sanitize: build $((built - start)) s, tests $(($(date +%s) - built)) s"
  exit 0
fi

targets=(sapmvs sapmvs_opencl_tests sapmvs_tests)
labels=()
if [ "${1:-}" = "--opencl" ]; then
  shift
  targets=(sapmvs sapmvs_opencl_tests)
  labels=(-L opencl)
fi
[ -n "${SAPMVS_DEPS_INSTALLED:-}" ] || bash scripts/install-deps.sh
if [ ! -f build/CMakeCache.txt ]; then
  flags=()
  # Nothing reads CI's debug information, and it is a fifth of the compile
  # time. -O1: the device tests' work is in the kernels, which PoCL
  # compiles; their build took 236 CPU seconds against 332 at -O2, their
  # run 101 against 94. Unity batches: 226 compile seconds for the stage
  # libraries against 400 file by file; the developer's scripts/build.sh
  # still compiles each file on its own, at -O2.
  [ "${CI:-}" = "true" ] && flags=(-DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -DNDEBUG" -DSAPMVS_UNITY_BUILD=ON)
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "${flags[@]}"
fi
# Only what the tests run (scripts/build.sh builds the profiling tools too).
start=$(date +%s)
cmake --build build --target "${targets[@]}" -j"$jobs"
built=$(date +%s)
export SAPMVS_REQUIRE_OPENCL="${SAPMVS_REQUIRE_OPENCL:-1}"
if [ "$SAPMVS_REQUIRE_OPENCL" = "1" ] && ! ./build/sapmvs devices >/dev/null 2>&1; then
  echo "test.sh: no OpenCL device found ($(./build/sapmvs devices 2>&1 | head -1));" \
    "without one, run the host tests: SAPMVS_REQUIRE_OPENCL=0 bash scripts/test.sh -L host" >&2
  exit 1
fi
ctest --test-dir build --output-on-failure -j"$jobs" "${labels[@]}" "$@"
echo "test.sh: build $((built - start)) s, tests $(($(date +%s) - built)) s"
