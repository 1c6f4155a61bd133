#!/usr/bin/env bash
# The demo: installs, builds, then runs the pipeline end to end on a built-in
# synthetic block (simulate -> info -> plan -> run -> evaluate against the
# simulated LiDAR), and describes a real aerial block (NGI, from ../shared)
# when it is there.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
out=out/demo
echo
echo "== sapmvs devices"
./build/sapmvs devices
echo
echo "== sapmvs simulate --preset tiny --out $out"
./build/sapmvs simulate --preset tiny --out "$out"
echo
echo "== sapmvs info $out/block.yaml"
./build/sapmvs info "$out/block.yaml"
echo
echo "== sapmvs plan $out/block.yaml"
./build/sapmvs plan "$out/block.yaml"
echo
echo "== sapmvs run $out/block.yaml --out $out/run"
./build/sapmvs run "$out/block.yaml" --out "$out/run" --restart
echo
echo "== sapmvs evaluate $out/run/cloud.ply --reference $out/truth/lidar.las --drop-above 2,0.5"
./build/sapmvs evaluate "$out/run/cloud.ply" --reference "$out/truth/lidar.las" --drop-above 2,0.5
echo
echo "== sapmvs info tests/blocks/ngi.yaml"
if [ -d ../shared/datasets/orthority_ngi_odm/ngi ]; then
  ./build/sapmvs info tests/blocks/ngi.yaml
else
  echo "(skipped: ../shared/datasets not found beside the checkout)"
fi
