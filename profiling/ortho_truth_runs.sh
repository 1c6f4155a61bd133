#!/bin/bash
# The table of profiling/results/ortho.md: `small`, `city` and `campus`
# simulated (with their true orthophoto), each run with the defaults, and
# each run's ortho.tif measured against the truth by ortho_truth (with the
# run's DSM, for the edges where it is right). Prints one Markdown row per
# preset and keeps each run's report.json and ortho_truth's JSON in WORK.
# Then the floor: the same ortho over the true surface taken onto each run's
# DSM cells (ortho_on_dsm --cells-of), one row per preset, "(truth on the
# run's cells)": what the DSM's cells and the images' pixels leave wrong
# at edges with no error of height.
#
#   profiling/ortho_truth_runs.sh [WORK]      # default /tmp/sapmvs_ortho
#
# From the checkout, after building build/sapmvs and build/profiling/ortho_truth
# (SAPMVS=..., ORTHO_TRUTH=... for others). Simulated blocks already in WORK
# are reused.
set -euo pipefail
work=${1:-/tmp/sapmvs_ortho}
sapmvs=${SAPMVS:-./build/sapmvs}
ortho_truth=${ORTHO_TRUTH:-./build/profiling/ortho_truth}
ortho_on_dsm=${ORTHO_ON_DSM:-./build/profiling/ortho_on_dsm}
mkdir -p "$work"
echo "| block | ortho cells | filled | shift median / p95 (GSD) | luminance error median / p95, bias | wrong side: roofs / ground | where the DSM is right: roofs / ground | where it has the step: roofs / ground | ortho time / run |"
echo "|---|---|---|---|---|---|---|---|---|"
rm -f "$work/floor_rows.md"
for preset in small city campus; do
  block="$work/sim_$preset"
  run="$work/run_$preset"
  [ -f "$block/truth/ortho.tif" ] || "$sapmvs" -q simulate --preset "$preset" --out "$block"
  "$sapmvs" -q run "$block/block.yaml" --out "$run" --restart > "$work/log_$preset.txt"
  "$ortho_truth" "$run/ortho.tif" --truth "$block/truth" --dsm "$run/dsm.tif" \
    --json "$work/truth_$preset.json" > "$work/truth_$preset.txt"
  cell=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["ortho"]["cell"])' \
    "$run/report.json")
  "$ortho_on_dsm" "$block/block.yaml" --dsm "$block/truth/dsm.tif" --cells-of "$run/dsm.tif" \
    --cell "$cell" --write-dsm "$work/floor_dsm_$preset.tif" --out "$work/floor_$preset.tif" \
    > /dev/null
  "$ortho_truth" "$work/floor_$preset.tif" --truth "$block/truth" \
    --dsm "$work/floor_dsm_$preset.tif" --json "$work/floor_$preset.json" > /dev/null
  python3 - "$preset" "$run/report.json" "$work/truth_$preset.json" "$work/floor_$preset.json" \
    "$work/floor_rows.md" <<'PY'
import json, sys
preset, report, truth, floor, floor_rows = sys.argv[1:]
r, t = json.load(open(report)), json.load(open(truth))
o = r["ortho"]
stages = {s["stage"]: s["wall_seconds"] for s in r["stages"]}
def share(side):
    return f'{100 * side["share"]:.1f} % of {side["cells"]:,}'
print(f'| `{preset}` | {o["width"]:,} × {o["height"]:,} of {o["cell"]:.3f} m '
      f'({t["ortho_cell"] / t["gsd"]:.2f} GSD) | {100 * o["filled_share"]:.1f} % | '
      f'{t["shift_median_gsd"]:.2f} / {t["shift_p95_gsd"]:.2f} ({t["tiles_used"]} tiles) | '
      f'{t["luminance_median"]:.1f} / {t["luminance_p95"]:.1f}, {t["luminance_bias"]:+.1f} | '
      f'{share(t["ghost_high"])} / {share(t["ghost_low"])} | '
      f'{share(t["ghost_high_dsm_right"])} / {share(t["ghost_low_dsm_right"])} | '
      f'{share(t["ghost_high_step_right"])} / {share(t["ghost_low_step_right"])} | '
      f'{stages["run ortho"]:.1f} / {r["total_seconds"]:.1f} s |')
t = json.load(open(floor))
with open(floor_rows, "a") as rows:
    print(f'| `{preset}`, the truth on the run\'s DSM cells | | | '
          f'{t["shift_median_gsd"]:.2f} / {t["shift_p95_gsd"]:.2f} ({t["tiles_used"]} tiles) | '
          f'{t["luminance_median"]:.1f} / {t["luminance_p95"]:.1f}, {t["luminance_bias"]:+.1f} | '
          f'{share(t["ghost_high"])} / {share(t["ghost_low"])} | '
          f'{share(t["ghost_high_dsm_right"])} / {share(t["ghost_low_dsm_right"])} | '
          f'{share(t["ghost_high_step_right"])} / {share(t["ghost_low_step_right"])} | – |',
          file=rows)
PY
done
echo
cat "$work/floor_rows.md"
