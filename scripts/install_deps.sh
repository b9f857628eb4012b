#!/usr/bin/env bash
# Installs the Debian packages weighted_icp needs, only those missing, so a
# second run costs nothing. Needs root (or sudo) on Debian bookworm.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libpcl-dev libflann-dev libeigen3-dev libboost-dev libboost-program-options-dev
  libopencv-dev libopencv-contrib-dev opencv-data libceres-dev
  libgtest-dev libbenchmark-dev
  python3-matplotlib python3-numpy
  pybind11-dev python3-pybind11 python3-pytest python3-mypy python3-open3d
  python3-dev python3-pil
  clang libclang-rt-14-dev libomp-14-dev  # clang-14 and libFuzzer (fuzz/); OpenMP for clang builds
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "[install_deps] all ${#packages[@]} packages present"
  exit 0
fi

echo "[install_deps] installing: ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
