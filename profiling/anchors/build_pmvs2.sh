#!/usr/bin/env bash
# Builds the real PMVS2 (Furukawa and Ponce's program, the paper's baseline)
# from its public source into build/anchors/, for profiling/versus_pmvs2.
# The source is never part of this repository: give the `program` folder of
# a checkout of https://github.com/pmoulon/CMVS-PMVS.
#
#   profiling/anchors/build_pmvs2.sh CMVS-PMVS/program [BUILD_DIR]
#
# BUILD_DIR defaults to build/ of this checkout; the binary lands in
# BUILD_DIR/anchors/pmvs2, where versus_pmvs2 looks for it. Needs a C++
# compiler, CMake and libjpeg (libjpeg-dev); about a minute on 2 cores.
set -euo pipefail
if [ $# -lt 1 ] || [ $# -gt 2 ]; then
  echo "usage: $0 CMVS-PMVS/program [BUILD_DIR]" >&2
  exit 2
fi
src=$(cd "$1" 2>/dev/null && pwd) || {
  echo "build_pmvs2: $1: no such folder (expected CMVS-PMVS's program/)" >&2
  exit 2
}
if [ ! -f "$src/CMakeLists.txt" ] || [ ! -f "$src/main/pmvs2.cc" ]; then
  echo "build_pmvs2: $src: not CMVS-PMVS's program/ (expected CMakeLists.txt and main/pmvs2.cc)" >&2
  exit 2
fi
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${2:-$root/build}
mkdir -p "$build/anchors"
build=$(cd "$build" && pwd)
bash "$root/scripts/apt-install.sh" build_pmvs2 libjpeg-dev
work="$build/anchors/pmvs-build"
# PMVS2's CMake files predate CMake 3.5; the policy floor lets current CMake
# configure them unchanged. Its sources are older C++ than today's compilers
# warn about; the warnings are theirs.
cmake -S "$src" -B "$work" -DCMAKE_BUILD_TYPE=Release -DCMAKE_POLICY_VERSION_MINIMUM=3.5 \
  -DCMAKE_CXX_FLAGS="-w" -DCMAKE_C_FLAGS="-w" >"$build/anchors/pmvs2-cmake.log" 2>&1 || {
  echo "build_pmvs2: cmake failed, see $build/anchors/pmvs2-cmake.log" >&2
  exit 1
}
jobs=$(nproc 2>/dev/null || echo 2)
cmake --build "$work" --target pmvs2 -j"$jobs" >"$build/anchors/pmvs2-build.log" 2>&1 || {
  echo "build_pmvs2: build failed, see $build/anchors/pmvs2-build.log" >&2
  exit 1
}
bin=$(find "$work" -type f -name pmvs2 -perm -u+x | head -1)
if [ -z "$bin" ]; then
  echo "build_pmvs2: no pmvs2 binary under $work" >&2
  exit 1
fi
cp "$bin" "$build/anchors/pmvs2.tmp"
mv "$build/anchors/pmvs2.tmp" "$build/anchors/pmvs2"
echo "build_pmvs2: $build/anchors/pmvs2 (from $src)"
