#!/usr/bin/env bash
# Installs what graspbed needs from Debian bookworm (only what is missing), then configures and builds.
# Idempotent: when everything is present it only runs an incremental build.
#   ./setup.sh               release build in build/
#   GRASPBED_SANITIZE=ON BUILD_DIR=build-asan ./setup.sh   ASan + UBSan build
set -euo pipefail
cd "$(dirname "$0")"

packages=(
  build-essential cmake ninja-build pkg-config git
  libmujoco-dev libmujoco-samples libqhull-dev   # physics (C API 2.2.2) and its stock tools
  libeigen3-dev libyaml-cpp-dev                  # linear algebra, configuration files
  libgtest-dev libgmock-dev libbenchmark-dev     # tests and benchmarks
  libcli11-dev nlohmann-json3-dev                # command line, JSON output
  libcairo2-dev                                  # PNG plots
  libegl-dev libegl-mesa0 libgl1-mesa-dri        # offscreen rendering: EGL, Mesa llvmpipe (no display/GPU)
  clang-14 libclang-rt-14-dev                    # libFuzzer target for the wire decoder
)

missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

build_dir="${BUILD_DIR:-build}"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" \
  -DGRASPBED_SANITIZE="${GRASPBED_SANITIZE:-OFF}" > "$build_dir.configure.log" 2>&1 \
  || { cat "$build_dir.configure.log"; exit 1; }
cmake --build "$build_dir" -j2
