#!/usr/bin/env bash
# Installs the Debian 12 packages gcpstereo builds against. Idempotent: when every package is
# already installed it changes nothing and does not touch the network.
# Usage: tools/install_deps.sh            (as root, or with sudo available)
set -euo pipefail

packages=(
  build-essential cmake pkg-config git python3
  libeigen3-dev libopencv-dev libpcl-dev libsuitesparse-dev libceres-dev libassimp-dev
  libyaml-cpp-dev libmaxflow-dev libcli11-dev libspdlog-dev nlohmann-json3-dev libtbb-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  # FLANN's k-d tree templates and the LZ4 they call (core/nearest_points.cc; libpcl-dev brings
  # both, named here because the code includes them itself).
  libflann-dev liblz4-dev
  # Optimised multi-threaded BLAS/LAPACK for CHOLMOD and Ceres (otherwise Debian may pick ATLAS
  # or the reference BLAS): CHOLMOD's 1536x1024 propagation solve 10.8 s -> 4.8 s.
  libopenblas0-pthread
  # The scene as a Snakemake workflow (pipeline/workflow/Snakefile) and its test; gcpstereo itself
  # does not need it.
  snakemake
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages present"
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install_deps: not root and no sudo; install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
echo "install_deps: installing ${missing[*]}"
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
