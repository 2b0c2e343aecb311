#!/usr/bin/env bash
# Installs the Debian packages jpcr needs (docs: ../shared/docs/environment.md), skipping those
# already present, so it is cheap to run every time. Needs root or sudo; talks only to apt.
set -euo pipefail

packages=(
  build-essential cmake pkg-config git
  libeigen3-dev libyaml-cpp-dev libgtest-dev libbenchmark-dev
  libceres-dev libopencv-dev libmrpt-obs-dev mrpt-common libcgal-dev
  cyclonedds-dev cyclonedds-tools
  python3-numpy python3-matplotlib
  clang libclang-rt-14-dev libomp-dev
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} Debian packages are present"
  exit 0
fi

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "setup: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
echo "setup: installing ${#missing[@]} missing package(s): ${missing[*]}"
"${sudo_cmd[@]}" apt-get update -qq
# env after sudo: sudo's env_reset would drop a DEBIAN_FRONTEND set before it (debconf prompts).
"${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
  "${missing[@]}"
echo "setup: done"
