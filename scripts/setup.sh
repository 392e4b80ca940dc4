#!/usr/bin/env bash
# Installs the Debian packages PLR needs (only those missing), then configures
# and builds into build/. Extra arguments go to CMake's configure step.
#   --asan  builds into build-asan/ with AddressSanitizer + UBSan (every test)
#   --tsan  builds into build-tsan/ with ThreadSanitizer (every test)
set -euo pipefail
cd "$(dirname "$0")/.."

build_dir=build
sanitizer=()
case "${1:-}" in
  --asan) build_dir=build-asan sanitizer=(-DPLR_ASAN=ON) && shift ;;
  --tsan) build_dir=build-tsan sanitizer=(-DPLR_TSAN=ON) && shift ;;
esac

packages=(
  build-essential cmake ninja-build pkg-config git clang-format lld
  libeigen3-dev libfcl-dev liboctomap-dev libsimbody-dev
  cyclonedds-dev cyclonedds-tools
  libyaml-cpp-dev libflatbuffers-dev flatbuffers-compiler
  libcli11-dev libspdlog-dev libfmt-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  liburdfdom-dev libsvm-dev
  libompl-dev libboost-serialization-dev libboost-filesystem-dev libboost-system-dev
  libexpat1-dev librsvg2-bin
  libboost-dev libzstd-dev zlib1g-dev
  chromium
  iproute2 openssl procps
  munge slurmctld slurmd slurm-client
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# Debian's node and npm, unless a node is there already (NodeSource's bundles npm).
command -v npm >/dev/null || missing+=(nodejs npm)
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# The independent MCAP reader the recording test checks against (@mcap/core),
# at the versions of the committed lock file; never fetched at build time.
if [[ ! -d tests/js/node_modules/@mcap/core ]]; then
  npm ci --prefix tests/js --no-audit --no-fund >/dev/null
fi

build_type=${PLR_BUILD_TYPE:-RelWithDebInfo}
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE="$build_type" "${sanitizer[@]}" "$@" >/dev/null
cmake --build "$build_dir" -j "$(nproc)"
