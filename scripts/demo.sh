#!/usr/bin/env bash
# The main job: installs what is missing, builds, then runs the embedded
# default end to end (generate the default 2 M-triangle plant, ingest it,
# bake its ground floor) into ${CELLBAKE_DEMO_OUT:-out/demo} and prints the
# database status. Idempotent: a rerun reuses the store and skips baked cells.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
build_dir="${CELLBAKE_BUILD_DIR:-build}"
out="${CELLBAKE_DEMO_OUT:-out/demo}"
echo "[demo] cellbake demo --out ${out}"
"${build_dir}/runner/cellbake" demo --out "${out}"
echo "[demo] status of ${out}/cells.db:"
"${build_dir}/runner/cellbake" status "${out}/cells.db"
