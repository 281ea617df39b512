#!/usr/bin/env bash
# Installs what sphfsi needs from Debian's archive (only what is missing) and builds it (Release).
# Idempotent: a second run with everything present does no apt work and an incremental build.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)

packages=(
  build-essential cmake pkg-config ccache git
  libeigen3-dev libzmq3-dev cppzmq-dev libmsgpack-cxx-dev libhdf5-dev
  doctest-dev libtomlplusplus-dev
  python3 python3-h5py python3-matplotlib python3-zmq python3-msgpack python3-numpy python3-scipy
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  # Through env: sudo resets the environment, and tzdata (matplotlib's) would otherwise ask for a time zone.
  $sudo_cmd env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  $sudo_cmd env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

build="${SPHFSI_BUILD_DIR:-$here/build}"
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
# Configured every time (seconds when nothing changed): a cache left by a configure that failed, by another
# build type, or by a checkout copied from elsewhere (whose tests name the old tree's paths) was reused as it
# was (a review, 2026-11-28); cmake refuses the last one loudly.
cmake -S "$here" -B "$build" -DCMAKE_BUILD_TYPE=Release "${launcher[@]}"
cmake --build "$build" -j"$(nproc)"
