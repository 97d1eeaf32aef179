#!/usr/bin/env bash
# Installs the Debian 12 packages cellbake needs, only those that are missing.
# Idempotent; prints what it does. Needs root (or sudo) when something is missing.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libtbb-dev libopenmesh-dev libcgal-dev libopenimageio-dev libosmesa6-dev
  libsqlite3-dev sqlite3 libtomlplusplus-dev libassimp-dev libmeshoptimizer-dev
  libcli11-dev nlohmann-json3-dev libspdlog-dev libxxhash-dev zlib1g-dev
  libgtest-dev libbenchmark-dev slurmctld slurmd slurm-client munge
  libglfw3-dev libimgui-dev libstb-dev xvfb xauth
  libembree-dev libegl-dev
  libzstd-dev libavif-dev libjxl-dev
  assimp-testmodels
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "[deps] all ${#packages[@]} packages present"
  exit 0
fi

echo "[deps] installing: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "[deps] done"
