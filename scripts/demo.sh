#!/usr/bin/env bash
# The demo: installs, builds, lists the OpenCL devices and describes a real
# aerial block (the NGI block from ../shared). It grows with the pipeline.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
echo
echo "== sapmvs devices"
./build/sapmvs devices
echo
echo "== sapmvs info tests/blocks/ngi.yaml"
if [ -d ../shared/datasets/orthority_ngi_odm/ngi ]; then
  ./build/sapmvs info tests/blocks/ngi.yaml
else
  echo "(skipped: ../shared/datasets not found beside the checkout)"
fi
