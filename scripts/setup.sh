#!/usr/bin/env bash
# Installs the Debian packages PLR needs (only those missing), then configures
# and builds into build/. Extra arguments go to CMake's configure step.
#   --asan  builds into build-asan/ with AddressSanitizer + UBSan (every test)
#   --tsan  builds into build-tsan/ with ThreadSanitizer (every test)
#   --runtime  only what the main job needs (plr, its plug-ins and tools):
#              no test-only packages, about a third of the build steps
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=build
sanitizer=()
runtime_only=false
while (($#)); do
  case "$1" in
    --asan) build_dir=build-asan sanitizer=(-DPLR_ASAN=ON) ;;
    --tsan) build_dir=build-tsan sanitizer=(-DPLR_TSAN=ON) ;;
    --runtime) runtime_only=true ;;
    *) break ;;
  esac
  shift
done

packages=(
  build-essential cmake ninja-build pkg-config git clang-format lld
  libeigen3-dev libfcl-dev liboctomap-dev libsimbody-dev
  cyclonedds-dev cyclonedds-tools
  libyaml-cpp-dev libflatbuffers-dev flatbuffers-compiler
  libcli11-dev libspdlog-dev libfmt-dev nlohmann-json3-dev
  liburdfdom-dev libsvm-dev
  libompl-dev libboost-serialization-dev libboost-filesystem-dev libboost-system-dev
  libexpat1-dev librsvg2-bin
  libboost-dev libzstd-dev zlib1g-dev
  iproute2 openssl procps
)
# What only the tests and benchmarks need: a browser for the dashboard's
# test, a single-node Slurm cluster, node for the independent MCAP reader.
test_packages=(
  libgtest-dev libgmock-dev libbenchmark-dev
  chromium
  munge slurmctld slurmd slurm-client
)
$runtime_only || packages+=("${test_packages[@]}")

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Debian's node and npm, unless a node is there already (NodeSource's bundles npm).
$runtime_only || command -v npm >/dev/null || missing+=(nodejs npm)
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The independent MCAP reader the recording test checks against (@mcap/core),
# at the versions of the committed lock file; never fetched at build time.
if ! $runtime_only && [[ ! -d tests/js/node_modules/@mcap/core ]]; then
  npm ci --prefix tests/js --no-audit --no-fund >/dev/null
fi

build_type=${PLR_BUILD_TYPE:-RelWithDebInfo}
if $runtime_only; then
  cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="$build_type" -DPLR_BUILD_TESTS=OFF \
    "${sanitizer[@]}" "$@" >/dev/null
  cmake --build "$build_dir" -j "$(nproc)" --target runtime
else
  cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="$build_type" -DPLR_BUILD_TESTS=ON \
    "${sanitizer[@]}" "$@" >/dev/null
  cmake --build "$build_dir" -j "$(nproc)"
fi
