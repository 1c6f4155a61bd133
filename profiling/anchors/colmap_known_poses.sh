#!/usr/bin/env bash
# A COLMAP undistorted folder with triangulated tie points for a block whose
# cameras are known (Strecha's ground truth, a simulated block): what
# OpenMVS reads (`versus_pmvs2 --openmvs`), which needs the points' tracks
# to choose each image's neighbours, and which `sapmvs export --format
# colmap` does not write. The cameras stay as given: COLMAP only matches
# SIFT features and triangulates them with the poses and intrinsics fixed.
#
#   profiling/anchors/colmap_known_poses.sh BLOCK OUT
#
# OUT gets images/ and sparse/ (COLMAP's binary model) and the export's
# sapmvs_frame.json, so that sapmvs reads it in the block's own frame; its
# work files go to OUT/work. Needs Debian's colmap and python3; a few minutes
# for 8 images of 6 MP on 2 cores.
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 BLOCK OUT" >&2
  exit 2
fi
block=$1
out=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
sapmvs=${SAPMVS:-$root/build/sapmvs}
for tool in colmap python3; do
  command -v "$tool" >/dev/null || {
    echo "colmap_known_poses: $tool not found (apt-get install colmap python3)" >&2
    exit 2
  }
done
[ -x "$sapmvs" ] || {
  echo "colmap_known_poses: $sapmvs: no sapmvs binary (build it, or set SAPMVS)" >&2
  exit 2
}
if [ -e "$out" ]; then
  echo "colmap_known_poses: $out exists; give a new folder" >&2
  exit 2
fi
work="$out/work"
mkdir -p "$work"
"$sapmvs" export "$block" --format colmap --out "$work/export" -q
read -r fx fy cx cy < <(awk '!/^#/ && NF >= 8 {print $5, $6, $7, $8; exit}' \
  "$work/export/sparse/0/cameras.txt")
model=$(awk '!/^#/ && NF >= 8 {print $2; exit}' "$work/export/sparse/0/cameras.txt")
if [ "$model" != PINHOLE ]; then
  echo "colmap_known_poses: expected one PINHOLE camera in the export, got $model" >&2
  exit 1
fi
colmap feature_extractor --database_path "$work/db.db" --image_path "$work/export/images" \
  --ImageReader.single_camera 1 --ImageReader.camera_model PINHOLE \
  --ImageReader.camera_params "$fx,$fy,$cx,$cy" --SiftExtraction.use_gpu 0 \
  >"$work/features.log" 2>&1
colmap exhaustive_matcher --database_path "$work/db.db" --SiftMatching.use_gpu 0 \
  >"$work/matches.log" 2>&1
# point_triangulator pairs the model's images with the database's by ID:
# the export numbers them in the block's order, the extractor in its own.
mkdir -p "$work/model" "$work/tri"
python3 - "$work" <<'EOF'
import shutil, sqlite3, sys
work = sys.argv[1]
ids = {name: i for i, name in sqlite3.connect(work + "/db.db").execute(
    "select image_id, name from images")}
lines = []
for line in open(work + "/export/sparse/0/images.txt").read().split("\n"):
    t = line.split()
    if not line.startswith("#") and len(t) == 10:
        t[0] = str(ids[t[9]])
        line = " ".join(t)
    lines.append(line)
open(work + "/model/images.txt", "w").write("\n".join(lines))
for f in ("cameras.txt", "points3D.txt"):
    shutil.copy(work + "/export/sparse/0/" + f, work + "/model/" + f)
EOF
colmap point_triangulator --database_path "$work/db.db" --image_path "$work/export/images" \
  --input_path "$work/model" --output_path "$work/tri" --Mapper.ba_refine_focal_length 0 \
  --Mapper.ba_refine_principal_point 0 --Mapper.ba_refine_extra_params 0 \
  >"$work/triangulate.log" 2>&1
mv "$work/export/images" "$out/images"
mv "$work/tri" "$out/sparse"
cp "$work/export/sapmvs_frame.json" "$out/"
echo "colmap_known_poses: $out"
