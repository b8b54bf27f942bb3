#!/usr/bin/env bash
# rotolidar set-up: installs Debian packages (idempotently), configures, builds, then runs one job.
#   bash .ci/setup.sh demo   -> build, then `rotolidar demo` on the built-in default scene
#   bash .ci/setup.sh test   -> build, then the test suite (ctest)
#   bash .ci/setup.sh core   -> build core/ alone (ROTOLIDAR_CORE_ONLY=ON), run its tests, and prove that no
#                               simulation library (MuJoCo, Embree, OSMesa) is linked
#   bash .ci/setup.sh deps   -> only install the Debian packages
set -euo pipefail
cd "$(dirname "$0")/.."

# The one package list of the project.
PACKAGES=(
  build-essential cmake pkg-config git
  libeigen3-dev libceres-dev libpcl-dev libopencv-dev libpcap-dev libyaml-cpp-dev libtbb-dev
  libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev
  libmujoco-dev libembree-dev libosmesa6-dev libgl-dev
)

install_deps() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then return 0; fi
  echo "[setup] installing ${#missing[@]} Debian packages: ${missing[*]}"
  local sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -q
  $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
}

BUILD_DIR=${ROTOLIDAR_BUILD_DIR:-build}
JOBS=${ROTOLIDAR_JOBS:-$(nproc)}

build() {
  if [ ! -f "$BUILD_DIR/CMakeCache.txt" ]; then
    cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release "$@"
  fi
  cmake --build "$BUILD_DIR" -j "$JOBS"
}

core_only() {
  BUILD_DIR=${BUILD_DIR}-core build -DROTOLIDAR_CORE_ONLY=ON
  local dir=${BUILD_DIR}-core
  ctest --test-dir "$dir" --output-on-failure -j "$JOBS"
  local bad
  bad=$(find "$dir" -type f -executable -name '*test*' -exec ldd {} \; | grep -i -E 'mujoco|embree|osmesa' || true)
  if [ -n "$bad" ]; then echo "[setup] core-only build links simulation libraries:"; echo "$bad"; exit 1; fi
  if grep -i -E 'mujoco|embree|osmesa' "$dir/core/CMakeFiles/rotolidar_core.dir/link.txt" 2>/dev/null; then exit 1; fi
  echo "[setup] core-only build: no MuJoCo, Embree or OSMesa linked"
}

job=${1:-demo}
install_deps
export ROTOLIDAR_DATA=${ROTOLIDAR_DATA:-$(cd .. && pwd)/shared/data}
case "$job" in
  deps) ;;
  core) core_only ;;
  demo) build; shift || true; "$BUILD_DIR/bench/rotolidar" demo "$@" ;;
  test) build
        ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$JOBS" ;;
  *) echo "usage: bash .ci/setup.sh [demo|test|core|deps]" >&2; exit 2 ;;
esac
