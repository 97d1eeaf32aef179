#!/usr/bin/env bash
# Installs the Debian 12 packages a job needs, only those that are missing.
#
#   scripts/install-deps.sh [GROUP...]     (default: build)
#
#   build  compilers, CMake, the lld linker and the libraries `cellbake` links; GLFW and
#          Dear ImGui for `cellbake-view` (built only when they are present)
#   test   GoogleTest, assimp's test models, Xvfb (the viewer screenshot test), ffmpeg (walk
#          videos: tests/test_walk), Chromium (the report in a browser: tests/test_report_browser;
#          ~110 s to install); the tests that need ffmpeg or Chromium skip without them
#   bench  Google Benchmark (-DCELLBAKE_BUILD_BENCH=ON); libavcodec, libavutil
#          and libswscale for bench_spatial_video (built only when present)
#   slurm  the Slurm daemons and munge (scripts/slurm-local.sh, tests/test_slurm)
#   browser  Node.js and Chromium: the glTF export's validator and three.js
#          checks (tests/test_export; their npm packages: scripts/install-node-tools.sh)
#
# When nothing is missing it runs no apt-get at all. Installing needs root:
# as root it runs apt-get, else through sudo when there is one; without sudo
# it prints the exact apt-get line to run as root and exits 1. Idempotent;
# says what it does. Not Debian (no dpkg-query): it checks nothing and lets
# CMake name what is missing.
set -euo pipefail

declare -A group_packages=(
  [build]="build-essential cmake ninja-build pkg-config git lld
           libtbb-dev libopenmesh-dev libcgal-dev libopenimageio-dev libosmesa6-dev
           libsqlite3-dev sqlite3 libtomlplusplus-dev libassimp-dev libmeshoptimizer-dev
           libcli11-dev nlohmann-json3-dev libspdlog-dev libxxhash-dev zlib1g-dev
           libembree-dev libegl-dev libzstd-dev libavif-dev libjxl-dev
           libglfw3-dev libimgui-dev libstb-dev"
  [test]="libgtest-dev assimp-testmodels xvfb xauth ffmpeg chromium"
  [bench]="libbenchmark-dev libavcodec-dev libavutil-dev libswscale-dev"
  [slurm]="slurmctld slurmd slurm-client munge"
  [browser]="nodejs chromium"
)

groups=("$@")
[ ${#groups[@]} -gt 0 ] || groups=(build)
packages=()
for g in "${groups[@]}"; do
  [ -n "${group_packages[$g]+x}" ] || { echo "[deps] unknown group '$g' (build, test, bench, slurm, browser)" >&2; exit 2; }
  # shellcheck disable=SC2206  # word splitting of the package list is intended
  packages+=(${group_packages[$g]})
done

if ! command -v dpkg-query >/dev/null 2>&1; then
  echo "[deps] no dpkg-query (not Debian?): not checking packages; CMake names what is missing"
  exit 0
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "[deps] ${groups[*]}: all ${#packages[@]} packages present"
  exit 0
fi

apt_line="apt-get update && apt-get install -y --no-install-recommends ${missing[*]}"
echo "[deps] ${groups[*]}: missing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if ! command -v sudo >/dev/null 2>&1; then
    echo "[deps] not root and no sudo: run as root" >&2
    echo "  $apt_line" >&2
    echo "[deps] then rerun; or build without this check: scripts/build.sh --no-deps" >&2
    exit 1
  fi
  SUDO="sudo"
fi
if ! { $SUDO env DEBIAN_FRONTEND=noninteractive apt-get update -q &&
       $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends "${missing[@]}"; }; then
  echo "[deps] apt-get failed; as root, run:" >&2
  echo "  $apt_line" >&2
  exit 1
fi
echo "[deps] done"
