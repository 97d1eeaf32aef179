#!/usr/bin/env bash
# Installs the npm packages the glTF export's checks use (tests/test_export.cpp,
# docs/benchmark-history.md): the Khronos glTF Validator (`gltf-validator`), `three`
# and `playwright-core` (scripts/validate-gltf.js, scripts/three-render-glb.js)
# into DIR/node_modules (default: $CELLBAKE_NODE_TOOLS, else node-tools/ in the
# source tree, which git ignores). Needs Node.js with npm and the network;
# the render check also needs Chromium (Debian package `chromium`). Tests find
# the packages through CELLBAKE_NODE_TOOLS, else in node-tools/, and skip
# with a message when they are not there.
#
#   scripts/install-node-tools.sh [DIR]
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
dir="${1:-${CELLBAKE_NODE_TOOLS:-$here/node-tools}}"
command -v npm >/dev/null 2>&1 || { echo "[node-tools] no npm: install Node.js (Debian: apt-get install nodejs npm)" >&2; exit 1; }
mkdir -p "$dir"
echo "[node-tools] installing gltf-validator three playwright-core into $dir"
npm install --prefix "$dir" --no-audit --no-fund gltf-validator three playwright-core
echo "[node-tools] done; tests look in $dir (export CELLBAKE_NODE_TOOLS=$dir when it is not $here/node-tools)"
