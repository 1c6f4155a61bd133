#!/usr/bin/env bash
# Installs, builds and runs the whole test suite (GoogleTest through CTest;
# OpenCL kernels run on the PoCL CPU device).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
jobs=$(nproc 2>/dev/null || echo 2)
ctest --test-dir build --output-on-failure -j"$jobs" "$@"
