#!/usr/bin/env bash
# Installs the Debian packages sapmvs builds and runs with. Idempotent: packages
# already present are left alone, so a second run only costs the apt checks.
#
#   scripts/install-deps.sh           everything: building, the tests, the
#                                     sanitizer and fuzzing toolchain, the
#                                     headless browser and the npm LAS readers
#                                     the tests check outputs with
#   scripts/install-deps.sh --build   only what building and running sapmvs
#                                     needs (scripts/demo.sh): on a fresh
#                                     Debian 12 machine clang, LLVM and the npm
#                                     packages were 40 s of the demo's 6 min
set -euo pipefail
build_only=0
case "${1:-}" in
  "") ;;
  --build) build_only=1 ;;
  *)
    echo "install-deps: unknown argument '$1'; expected none or --build" >&2
    exit 2
    ;;
esac

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  pocl-opencl-icd ocl-icd-opencl-dev opencl-clhpp-headers opencl-c-headers clinfo
  libeigen3-dev libopencv-dev libflann-dev libjpeg-dev libpng-dev
  libgdal-dev gdal-bin libcli11-dev libyaml-cpp-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  # `mpirun -np N sapmvs run` (optional: without them sapmvs builds as one process).
  openmpi-bin libopenmpi-dev
)
# scripts/fuzz.sh and test.sh --sanitize: clang with its sanitizer and
# libFuzzer runtimes and its OpenMP; the symbolizer for sanitizer reports.
# The tests that open report.html in a headless browser (12 s of apt).
[ "$build_only" = 1 ] || PACKAGES+=(clang libclang-rt-14-dev libomp-dev llvm chromium)

bash "$(dirname "$0")/apt-install.sh" install-deps "${PACKAGES[@]}"
[ "$build_only" = 0 ] || exit 0

# The independent LAS readers the tests check cloud.las with, from npm: copc.js
# and @loaders.gl/las (the loader behind deck.gl and kepler.gl; @loaders.gl/las
# 4.4.x asks for @loaders.gl/core ~4.4.0, so both are pinned to 4.4.5). Into
# build/npm, never system-wide. Without the npm registry the LAS test says
# skipped; nothing else needs them.
# Node and npm only for that test, so a failure here does not stop the build.
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
if ! command -v npm >/dev/null 2>&1; then
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends nodejs npm \
    >/dev/null 2>&1 || echo "install-deps: warning: could not install nodejs/npm"
fi
cd "$(dirname "$0")/.."
NPM_PACKAGES=(copc@0.0.8 @loaders.gl/core@4.4.5 @loaders.gl/las@4.4.5)
if command -v npm >/dev/null 2>&1 &&
  { [ ! -d build/npm/node_modules/copc ] || [ ! -d build/npm/node_modules/@loaders.gl/las ]; }; then
  mkdir -p build/npm
  if npm install --prefix build/npm --no-audit --no-fund --loglevel=error "${NPM_PACKAGES[@]}" \
    >/dev/null 2>&1; then
    echo "install-deps: copc.js and @loaders.gl/las (LAS readers for the tests) in build/npm"
  else
    echo "install-deps: warning: npm could not install ${NPM_PACKAGES[*]}; the independent LAS test will be skipped"
  fi
fi
