#!/usr/bin/env bash
# Installs what graspbed needs from Debian 12 "bookworm" (only what is missing), then configures and
# builds. Enough on a bare bookworm (debootstrap --variant=minbase, nothing else installed): the
# build, the tests and the main command need nothing beyond this list. Run as root, or as a user
# with sudo. Idempotent: when everything is present it only runs an incremental build.
#   ./setup.sh               release build in build/
#   GRASPBED_SANITIZE=ON BUILD_DIR=build-asan ./setup.sh   ASan + UBSan build
set -euo pipefail
cd "$(dirname "$0")"

packages=(
  build-essential cmake ninja-build pkg-config git ca-certificates  # (git over https needs the CAs)
  libmujoco-dev libqhull-dev                     # physics (C API 2.2.2); mujoco::mujoco names qhull's headers
  libgl-dev libopengl-dev libglx-dev             # mujocoConfig.cmake's find_dependency(OpenGL); libmujoco-dev
                                                 # does not pull them in
  libmujoco-samples                              # mujoco-compile, mujoco-testspeed: tests run the model in them
  libeigen3-dev libyaml-cpp-dev                  # linear algebra, configuration files
  libgtest-dev libgmock-dev libbenchmark-dev     # tests and benchmarks
  libcli11-dev nlohmann-json3-dev                # command line, JSON output
  libcairo2-dev fonts-dejavu-core                # plots are drawn with cairo; their labels need a font
  libpng-dev                                     # PNG files (plots, stills): written with libpng's fast settings
  zlib1g-dev                                     # the dataset's .npz archives: zlib's crc32
  libegl-dev libegl-mesa0 libgl1-mesa-dri        # offscreen rendering: EGL, Mesa llvmpipe (no display/GPU)
  ffmpeg                                         # videos: run --video pipes frames to it; tests read them with ffprobe
  libglfw3-dev xvfb xauth xdotool                # graspbed view: a window (GLFW); its tests run under xvfb-run and type keys with xdotool
  clang-14 libclang-rt-14-dev                    # libFuzzer targets (wire decoder, scenario loader): build-fuzz/
  python3 python3-dev pybind11-dev               # the graspbed Python module; python3 runs the install tests
  strace                                         # the install test traces file access where unshare is refused
  python3-numpy python3-pytest                   # its signals as numpy arrays; its tests
  python3-sklearn python3-matplotlib             # training the learned slip cue (python/train_slip_model.py), its PR plots
  chromium                                       # graspbed report's test loads the HTML report in headless chromium
)

missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if ((${#missing[@]})); then
  as_root=()
  if [ "$(id -u)" -ne 0 ]; then
    if ! command -v sudo > /dev/null; then
      echo "setup: these Debian packages are missing and installing them needs root: ${missing[*]}" >&2
      echo "setup: run ./setup.sh as root (there is no sudo here), or install them and run it again" >&2
      exit 1
    fi
    as_root=(sudo)
  fi
  echo "setup: installing ${missing[*]}"
  "${as_root[@]}" apt-get update -qq
  "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

build_dir="${BUILD_DIR:-build}"
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="${BUILD_TYPE:-Release}" \
  -DGRASPBED_SANITIZE="${GRASPBED_SANITIZE:-OFF}" > "$build_dir.configure.log" 2>&1 \
  || { cat "$build_dir.configure.log"; exit 1; }
cmake --build "$build_dir" -j2

# The libFuzzer targets' clang tree (build-fuzz/) is not built here: only the tests use it, and
# ctest's fuzz.build_tree builds it before scenario_fuzz (fuzz/build_fuzz_tree.sh).
