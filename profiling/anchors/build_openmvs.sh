#!/usr/bin/env bash
# Builds OpenMVS's DensifyPointCloud and InterfaceCOLMAP (CPU only) from
# their public sources into build/anchors/openmvs/, for
# `profiling/versus_pmvs2 --openmvs`. The sources are never part of this
# repository: give a checkout of https://github.com/cdcseacave/openMVS and a
# folder holding vcglib's `vcg`, `wrap` and `eigenlib` folders
# (https://github.com/cnr-isti-vclab/vcglib).
#
#   profiling/anchors/build_openmvs.sh openMVS vcglib [BUILD_DIR]
#
# BUILD_DIR defaults to build/ of this checkout. Installs the Debian
# packages OpenMVS needs beyond sapmvs's (CGAL, Boost); about 3 minutes on
# 2 cores.
set -euo pipefail
if [ $# -lt 2 ] || [ $# -gt 3 ]; then
  echo "usage: $0 openMVS vcglib [BUILD_DIR]" >&2
  exit 2
fi
# The absolute path of folder $1, or a line naming it and what $2 says was
# expected there.
folder() {
  (cd "$1" 2>/dev/null && pwd) || {
    echo "build_openmvs: $1: no such folder (expected $2)" >&2
    exit 2
  }
}
src=$(folder "$1" "a checkout of openMVS")
if [ ! -f "$src/CMakeLists.txt" ] || [ ! -d "$src/apps/DensifyPointCloud" ]; then
  echo "build_openmvs: $src: not openMVS (expected CMakeLists.txt and apps/DensifyPointCloud)" >&2
  exit 2
fi
vcg=$(folder "$2" "vcglib's vcg, wrap and eigenlib")
if [ ! -d "$vcg/vcg" ] || [ ! -d "$vcg/wrap" ]; then
  echo "build_openmvs: $vcg: not vcglib (expected its vcg and wrap folders)" >&2
  exit 2
fi
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${3:-$root/build}
mkdir -p "$build/anchors"
build=$(cd "$build" && pwd)
bash "$root/scripts/apt-install.sh" build_openmvs libcgal-dev libboost-iostreams-dev \
  libboost-program-options-dev libboost-system-dev libboost-serialization-dev libjpeg-dev \
  libpng-dev libtiff-dev libopencv-dev libeigen3-dev
work="$build/anchors/openmvs-build"
cmake -S "$src" -B "$work" -DCMAKE_BUILD_TYPE=Release -DVCG_ROOT="$vcg" \
  -DOpenMVS_USE_CUDA=OFF -DOpenMVS_USE_PYTHON=OFF -DOpenMVS_USE_BREAKPAD=OFF \
  -DOpenMVS_USE_OPENGL=OFF >"$build/anchors/openmvs-cmake.log" 2>&1 || {
  echo "build_openmvs: cmake failed, see $build/anchors/openmvs-cmake.log" >&2
  exit 1
}
jobs=$(nproc 2>/dev/null || echo 2)
cmake --build "$work" --target DensifyPointCloud InterfaceCOLMAP -j"$jobs" \
  >"$build/anchors/openmvs-build.log" 2>&1 || {
  echo "build_openmvs: build failed, see $build/anchors/openmvs-build.log" >&2
  exit 1
}
mkdir -p "$build/anchors/openmvs"
for name in DensifyPointCloud InterfaceCOLMAP; do
  bin=$(find "$work" -type f -name "$name" -perm -u+x | head -1)
  if [ -z "$bin" ]; then
    echo "build_openmvs: no $name binary under $work" >&2
    exit 1
  fi
  cp "$bin" "$build/anchors/openmvs/$name.tmp"
  mv "$build/anchors/openmvs/$name.tmp" "$build/anchors/openmvs/$name"
done
echo "build_openmvs: $build/anchors/openmvs/DensifyPointCloud and InterfaceCOLMAP (from $src)"
