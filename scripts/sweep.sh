#!/usr/bin/env bash
# Parameter sweep: bakes a few cells of the demo plant with one parameter
# changed at a time (cube-face size, simplification depth error, JPEG quality,
# near-field budget), verifies each bake, and collects (bake seconds, stored
# bytes, error) per variant into OUT/sweep.csv and a speed-vs-error plot
# OUT/sweep.svg (written by `cellbake plot`, the verify report's plot writer).
#
#   scripts/sweep.sh [OUT] [CELLS] [TRIANGLES]
#   (defaults: /tmp/cellbake-sweep, cells 1-4, a 500,000-triangle plant)
# Environment: CELLBAKE (the binary, default build/runner/cellbake), THREADS,
# VIEWS (views per cell, default 4), SIZE (verify image size, default 256x192).
set -euo pipefail

here="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-/tmp/cellbake-sweep}"
cells="${2:-1-4}"
triangles="${3:-500000}"
cellbake="${CELLBAKE:-$here/build/runner/cellbake}"
threads="${THREADS:-0}"
views="${VIEWS:-4}"
size="${SIZE:-256x192}"
mkdir -p "$out"

# The geometry store, once (the demo's plant: generate + ingest).
if [[ ! -f "$out/base/plant.store.db" ]]; then
  mkdir -p "$out/base"
  "$cellbake" generate plant --triangles "$triangles" --seed 1 --out "$out/base/plant.ply" --store "$out/base/plant.store.db"
fi

# name|overrides (space-separated --set values). The first line is the reference.
variants=(
  "reference|sample.face_size=512"
  "face256|sample.face_size=256"
  "face1024|sample.face_size=1024"
  "depth0.002|sample.face_size=512 simplify.depth_error_relative=0.002"
  "depth0.05|sample.face_size=512 simplify.depth_error_relative=0.05"
  "quality50|sample.face_size=512 encode.quality=50"
  "quality95|sample.face_size=512 encode.quality=95"
  "near20k|sample.face_size=512 near.budget=20000"
  "near300k|sample.face_size=512 near.budget=300000"
)

csv="$out/sweep.csv"
echo "variant,parameter,overrides,cells,bake_seconds,bytes,far_triangles,psnr_median_db,ssim_median,hole_fraction_median,skin_fraction_median,ms_impostor_median" > "$csv"
for v in "${variants[@]}"; do
  name="${v%%|*}"
  overrides="${v#*|}"
  sets=()
  for s in $overrides; do sets+=(--set "$s"); done
  db="$out/$name/cells.db"
  mkdir -p "$out/$name"
  echo "== $name: $overrides"
  # The demo's region and cells (configs/plant-demo.toml), every other key at its default.
  "$cellbake" bake --store "$out/base/plant.store.db" --region 4,6,1.7,40,34,1.7 --cell-size 4 --out "$db" \
    --cells "$cells" --threads "$threads" --quiet "${sets[@]}"
  "$cellbake" verify "$db" --walk-seconds 0 --report "$out/$name/report" --views-per-cell "$views" --size "$size" \
    --threads "$threads" --quiet > /dev/null
  json="$out/$name/report/report.json"
  # The parameter a variant changes: the last override's key (the reference changes none).
  last="${overrides##* }"
  parameter="${last%%=*}"
  [[ "$name" == reference ]] && parameter="reference"
  jq -r --arg name "$name" --arg parameter "$parameter" --arg overrides "$overrides" '
    [ $name, $parameter, $overrides, (.cells | length),
      ([.cells[].bake_seconds_total] | add),
      ([.cells[].bytes] | add),
      ([.cells[].far_triangles] | add),
      (.summary.psnr_db.median // "inf"), .summary.ssim.median, .summary.hole_fraction.median,
      .summary.skin_fraction.median, .summary.ms_impostor.median ] | @csv' "$json" | tr -d '"' >> "$csv"
done

"$cellbake" plot "$csv" --x bake_seconds --y psnr_median_db --series parameter --label variant \
  --title "Bake time vs error (cells $cells)" --out "$out/sweep.svg"
"$cellbake" plot "$csv" --x bytes --y psnr_median_db --series parameter --label variant \
  --title "Stored bytes vs error (cells $cells)" --out "$out/sweep_bytes.svg"
column -s, -t < "$csv" | cut -c1-200
echo "results: $csv, $out/sweep.svg, $out/sweep_bytes.svg"
