#!/usr/bin/env bash
# Fuzzes the input readers with libFuzzer (clang, AddressSanitizer and
# UndefinedBehaviorSanitizer): builds the targets of tests/fuzz into
# build/fuzz, seeds each corpus from the shared data sets, tests/blocks and
# sapmvs's own writers, and runs the targets one at a time for N executions.
#
#   scripts/fuzz.sh [--runs N] [--max-time S] [--max-len BYTES] [--lanes L] [target...]
#
# Targets: block_yaml block_pmvs colmap_text colmap_binary block_strecha
# block_opensfm ply las program_cache (all by default). The corpora grow in
# build/fuzz/corpus/TARGET across runs; a finding is saved as
# build/fuzz/artifacts/TARGET-crash-* (replay: build/fuzz/tests/fuzz/fuzz_TARGET FILE)
# and the script exits 1. Not a CI step: 1 M runs of one target take 5 to 15
# minutes on an idle core (the block readers are the slow ones), far longer
# on a busy machine; --max-time S stops each target after S seconds instead
# (the summary says how many executions that was). Runs under `nice`, one
# target at a time (--lanes L: L at a time). The inputs' files go to $TMPDIR
# (default /dev/shm: on a disk, truncating files costs more than the
# readers). ASan keeps no allocation stacks (malloc_context_size=0, a third
# faster); replay a finding without it to see them.
set -euo pipefail
cd "$(dirname "$0")/.."

runs=1000000
max_len=16384
lanes=1
max_time=0
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) runs="$2"; shift 2 ;;
    --max-len) max_len="$2"; shift 2 ;;
    --lanes) lanes="$2"; shift 2 ;;
    --max-time) max_time="$2"; shift 2 ;;
    -h|--help) awk 'NR > 1 && /^#/ { print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1 (expected --runs N, --max-time S, --max-len BYTES, --lanes L)" >&2; exit 1 ;;
    *) targets+=("$1"); shift ;;
  esac
done
all=(block_yaml block_pmvs colmap_text colmap_binary block_strecha block_opensfm ply las program_cache)
[ ${#targets[@]} -gt 0 ] || targets=("${all[@]}")
for t in "${targets[@]}"; do
  [[ " ${all[*]} " == *" $t "* ]] || { echo "fuzz.sh: unknown target '$t' (expected one of: ${all[*]})" >&2; exit 1; }
done

command -v clang++ >/dev/null || bash scripts/install-deps.sh
build=build/fuzz
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DSAPMVS_FUZZ=ON -DSAPMVS_BUILD_TESTS=OFF -DSAPMVS_BUILD_BENCHMARKS=OFF "${launcher[@]}" >/dev/null
fi
nice cmake --build "$build" --target fuzz_all -j"$(nproc 2>/dev/null || echo 2)"

shared=../shared/datasets
seeds="$build/seeds"
rm -rf "$seeds"
mkdir -p "$seeds" "$build/artifacts"
"$build/tests/fuzz/fuzz_make_seeds" "$seeds"
sep=$'\n--8<--\n'
join() {  # join FILE... : the files' bytes with the targets' separator between
  local first=1
  for f in "$@"; do
    [ $first = 1 ] || printf '%s' "$sep"
    cat "$f"
    first=0
  done
}
# The stand-in image files the targets create (readers only look them up).
names="$build/image_names.txt"
{
  printf '%s\n' 0000.jpg 0001.jpg 0002.jpg a.jpg
  [ -d "$shared" ] && find "$shared" -type f \( -iname '*.jpg' -o -iname '*.tif' -o -iname '*.png' \) -printf '%f\n'
} | sort -u >"$names"
export SAPMVS_FUZZ_IMAGE_NAMES="$PWD/$names"

# block.yaml + orientation, pointed at the target's layout (images/,
# orientation.txt) so that the seeds get past the file lookups.
mkdir -p "$seeds/block_yaml"
yaml_seed() {  # yaml_seed NAME BLOCK ORIENTATION
  sed -e 's|^\( *file:\).*|\1 orientation.txt|' -e '/^dem:/d' -e 's|^images:.*|images: images|' "$2" \
    >"$seeds/tmp.yaml"
  join "$seeds/tmp.yaml" "$3" >"$seeds/block_yaml/$1"
}
[ -f "$shared/orthority_ngi_odm/ngi/camera_pos_ori.txt" ] &&
  yaml_seed ngi tests/blocks/ngi.yaml "$shared/orthority_ngi_odm/ngi/camera_pos_ori.txt"
yaml_seed odm tests/blocks/odm.yaml tests/blocks/odm_xyz_opk.txt
printf 'cameras:\n  - {name: a, width: 8, height: 6, fx: 10, fy: 10, cx: 4, cy: 3}\n  - {name: b, width: 8, height: 6, focal_mm: 5, pixel_um: 2}\nimages: [0000.jpg, 0001.jpg]\norientation: {file: orientation.txt, type: rotation, rotation: world-to-camera-opencv}\n' >"$seeds/tmp.yaml"
printf '0000.jpg 0 0 5 1 0 0 0 1 0 0 0 1 a\n0001.jpg 1 0 5 1 0 0 0 1 0 0 0 1 b\n' >"$seeds/tmp.txt"
join "$seeds/tmp.yaml" "$seeds/tmp.txt" >"$seeds/block_yaml/rotation"
printf 'camera: {width: 8, height: 6, fx: 10, fy: 10, cx: 4, cy: 3, distortion: {k1: 0.1}}\nground_height: 2\nimages: images\norientation: {file: orientation.txt, type: projection}\n' >"$seeds/tmp.yaml"
printf 'a.jpg 10 0 4 0 0 10 3 0 0 0 1 -5\n' >"$seeds/tmp.txt"
join "$seeds/tmp.yaml" "$seeds/tmp.txt" >"$seeds/block_yaml/projection"
rm -f "$seeds/tmp.yaml" "$seeds/tmp.txt"

mkdir -p "$seeds/block_strecha" "$seeds/block_opensfm"
herz="$shared/strecha_herzjesu/Herz-Jesus-P8/gt_dense_cameras"
if [ -d "$herz" ]; then
  cp "$herz/0000.jpg.camera" "$seeds/block_strecha/one"
  join "$herz/0000.jpg.camera" "$herz/0001.jpg.camera" "$herz/0002.jpg.camera" >"$seeds/block_strecha/three"
fi
odm="$shared/orthority_ngi_odm/odm/opensfm/reconstruction.json"
[ -f "$odm" ] && cp "$odm" "$seeds/block_opensfm/odm.json"
printf '[{"cameras": {"c": {"projection_type": "brown", "width": 8, "height": 6, "focal_x": 1.2, "focal_y": 1.2, "c_x": 0, "c_y": 0, "k1": 0, "k2": 0, "p1": 0, "p2": 0, "k3": 0}}, "shots": {"0000.jpg": {"camera": "c", "rotation": [0, 0, 0], "translation": [0, 0, 5]}}, "reference_lla": {"latitude": 50, "longitude": 7, "altitude": 100}}]\n' \
  >"$seeds/block_opensfm/small.json"

summary="$build/summary.txt"
: >"$summary"
if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi
export ASAN_OPTIONS="malloc_context_size=0${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
fuzz_one() {  # fuzz_one TARGET: appends its line to the summary; status 1 on a finding
  local t=$1 corpus="$build/corpus/$1" log="$build/$1.log" start rc secs execs line
  mkdir -p "$corpus"
  start=$(date +%s)
  echo "fuzz.sh: $t: $runs runs (log $log)"
  set +e
  nice "$build/tests/fuzz/fuzz_$t" -runs="$runs" -max_total_time="$max_time" -max_len="$max_len" -timeout=20 -rss_limit_mb=2560 \
    -print_final_stats=1 -artifact_prefix="$build/artifacts/$t-" "$corpus" "$seeds/$t" >"$log" 2>&1
  rc=$?
  set -e
  secs=$(($(date +%s) - start))
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  line="$t: ${execs:-?} executions in ${secs} s, exit $rc, corpus $(ls "$corpus" | wc -l) files"
  [ $rc -eq 0 ] || line="$line: FINDING, see $log and $build/artifacts/"
  echo "fuzz.sh: $line"
  echo "$line" >>"$summary"
  return $((rc != 0))
}
# Lane i takes targets i, i+L, i+2L, ...
pids=()
for ((lane = 0; lane < lanes; lane++)); do
  (
    s=0
    for ((i = lane; i < ${#targets[@]}; i += lanes)); do fuzz_one "${targets[$i]}" || s=1; done
    exit $s
  ) &
  pids+=($!)
done
status=0
for p in "${pids[@]}"; do wait "$p" || status=1; done
echo "fuzz.sh: summary in $summary"
exit $status
