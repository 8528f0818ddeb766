#!/usr/bin/env bash
# The one place semslam's Debian (bookworm) dependencies are listed.
# Idempotent: installs only the packages that are missing.
#   scripts/install-deps.sh [--slurm]   # --slurm: also Slurm and munge, for the test of scripts/city.sbatch on a
#                                       # one-node cluster (scripts/slurm-local.sh; CI does)
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config ccache git
  clang-14 libclang-rt-14-dev
  libopencv-dev
  libeigen3-dev
  libceres-dev
  libgeographiclib-dev
  nlohmann-json3-dev
  libcli11-dev
  libspdlog-dev libfmt-dev
  libyaml-cpp-dev
  libtbb-dev
  libnanoflann-dev
  libboost-graph-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libosmium2-dev zlib1g-dev libexpat1-dev libbz2-dev
  python3-dev python3-numpy pybind11-dev
  python3-distributed
)
for a in "$@"; do
  case "$a" in
    --slurm) packages+=(slurmctld slurmd slurm-client munge) ;;
    *) echo "usage: scripts/install-deps.sh [--slurm]" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install-deps: installing ${#missing[@]} missing package(s): ${missing[*]}"
sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  if ! command -v sudo >/dev/null; then
    echo "install-deps: installing needs root, and there is no sudo here: run this script as root, or install" \
      "the packages above with the system's tools" >&2
    exit 1
  fi
  sudo_cmd=(sudo)
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
