#!/usr/bin/env bash
# Rebuilds the real UAV block the benchmarks use: Caliterra, 77 nadir photos
# (75 published whole) of a hand-flown survey, Canon SX260 HS, 4000x3000,
# geotagged, published by OpenDroneMap-ja as odm_data_caliterra. Oriented
# here with Debian's COLMAP on the CPU at 2000x1500 and aligned to its GPS
# in a local east-north-up frame; the data stays out of the repository.
#
#   profiling/anchors/uav_caliterra.sh SOURCE OUT
#
# SOURCE: a clone of odm_data_caliterra, its .git folder, or a folder of its
# JPEGs. OUT: the work folder; OUT/dense is the undistorted COLMAP project
# that `sapmvs run` and profiling/versus_pmvs2 read. Needs colmap and
# python3-numpy (apt-get install colmap python3-numpy). About 30 min on 2
# cores.
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 SOURCE OUT" >&2
  exit 2
fi
src=$1
out=$2
command -v colmap >/dev/null || { echo "$0: colmap not found (apt-get install colmap)" >&2; exit 1; }
export QT_QPA_PLATFORM=offscreen
threads=$(nproc 2>/dev/null || echo 2)
here=$(cd "$(dirname "$0")" && pwd)
# Debian's python3 (python3-numpy); another python3 first on PATH may lack numpy.
py=python3
[ -x /usr/bin/python3 ] && py=/usr/bin/python3
$py -c "import numpy" 2>/dev/null || { echo "$0: python3-numpy not found (apt-get install python3-numpy)" >&2; exit 1; }
mkdir -p "$out/images"

# Images: from a git folder (a snapshot may lack some blobs: those are left
# out and named) or a plain folder.
gitdir=""
if [ -d "$src/.git" ]; then gitdir="$src/.git"; elif [ -f "$src/HEAD" ]; then gitdir="$src"; fi
if [ -n "$gitdir" ]; then
  # The photos lie at the top of early commits and under images/ of later ones.
  for path in $(git --git-dir="$gitdir" ls-tree -r --name-only HEAD | grep -i '\.jpg$'); do
    f=$(basename "$path")
    [ -s "$out/images/$f" ] && continue
    if git --git-dir="$gitdir" cat-file -e "HEAD:$path" 2>/dev/null; then
      git --git-dir="$gitdir" cat-file blob "HEAD:$path" >"$out/images/$f.part"
      mv "$out/images/$f.part" "$out/images/$f"
    else
      echo "$0: $path is not in the snapshot; left out"
    fi
  done
else
  cp -n "$src"/*.[jJ][pP][gG] "$out/images/"
fi
count=$(ls "$out/images" | wc -l)
echo "$0: $count images in $out/images"
if [ "$count" -eq 0 ]; then
  echo "$0: $src: no JPEG photos found (expected *.jpg at its top or under images/)" >&2
  exit 1
fi

db=$out/database.db
if [ ! -f "$out/.features" ]; then
  rm -f "$db"
  # One camera for the flight; OPENCV (k1 k2 p1 p2), as the SfM calibrates it.
  colmap feature_extractor --database_path "$db" --image_path "$out/images" \
    --ImageReader.single_camera 1 --ImageReader.camera_model OPENCV \
    --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads "$threads" \
    --SiftExtraction.max_image_size 2000 --SiftExtraction.max_num_features 6000 >"$out/features.log" 2>&1
  touch "$out/.features"
fi
if [ ! -f "$out/.matches" ]; then
  # The images' GPS positions pick the pairs: 20 nearest, as a flight's
  # neighbours along and across the strips.
  colmap spatial_matcher --database_path "$db" --SiftMatching.use_gpu 0 \
    --SiftMatching.num_threads "$threads" --SpatialMatching.is_gps 1 \
    --SpatialMatching.max_num_neighbors 20 --SpatialMatching.max_distance 200 >"$out/matches.log" 2>&1
  touch "$out/.matches"
fi
if [ ! -f "$out/sparse/0/images.bin" ]; then
  mkdir -p "$out/sparse"
  colmap mapper --database_path "$db" --image_path "$out/images" --output_path "$out/sparse" \
    --Mapper.num_threads "$threads" >"$out/mapper.log" 2>&1
fi
if [ ! -f "$out/aligned/images.bin" ]; then
  mkdir -p "$out/aligned" "$out/sparse_txt"
  # East-north-up at the GPS position of the model's first image, metres. Not COLMAP's
  # model_aligner to GPS: this camera's GPS altitude climbs 112 m over a
  # flight held at one height, and aligning to it tilted the block by 25
  # degrees. The strips' plane is levelled instead and only GPS east and
  # north are fitted (level_to_gps.py); heights are above the median sparse
  # point.
  colmap model_converter --input_path "$out/sparse/0" --output_path "$out/sparse_txt" \
    --output_type TXT >"$out/aligner.log" 2>&1
  $py "$here/level_to_gps.py" "$out/sparse_txt" "$db" "$out/level_to_gps.txt" | tee -a "$out/aligner.log"
  colmap model_transformer --input_path "$out/sparse/0" --output_path "$out/aligned" \
    --transform_path "$out/level_to_gps.txt" >>"$out/aligner.log" 2>&1
fi
if [ ! -f "$out/dense/sparse/images.bin" ]; then
  rm -rf "$out/dense"
  colmap image_undistorter --image_path "$out/images" --input_path "$out/aligned" \
    --output_path "$out/dense" --output_type COLMAP --max_image_size 2000 >"$out/undistort.log" 2>&1
fi
colmap model_analyzer --path "$out/dense/sparse" 2>&1 | sed -n 's/^.*\] //p' | tee "$out/model.txt"
