#!/usr/bin/env bash
# The main job: installs what is missing, builds, then runs the embedded
# default end to end (generate the default plant, ingest it) into out/demo.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
build_dir="${CELLBAKE_BUILD_DIR:-build}"
out="${CELLBAKE_DEMO_OUT:-out/demo}"
mkdir -p "${out}"
echo "[demo] generating and ingesting the default plant into ${out}"
"${build_dir}/runner/cellbake" generate plant --triangles 2000000 --seed 1 --out "${out}/plant.ply" --store "${out}/plant.store.db"
echo "[demo] done: geometry store ${out}/plant.store.db"
