#!/usr/bin/env bash
# Installs what cncstream needs to build and test on Debian bookworm.
# Idempotent: asks apt only for what is missing.
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config git
  libboost-dev libserialport-dev libusb-1.0-0-dev
  libglfw3-dev libgl-dev libegl-dev libopengl-dev xvfb
  libegl-mesa0 libgl1-mesa-dri  # llvmpipe for the depth-buffer CL engine (src/gl/) without a GPU
  libsqlite3-dev libcli11-dev nlohmann-json3-dev libtomlplusplus-dev
  libspdlog-dev libfmt-dev libtbb-dev libpng-dev nettle-dev
  libgtest-dev libgmock-dev googletest libbenchmark-dev
  tmux  # the terminal jog tests drive `cncstream jog` in a tmux session
  chromium chromium-driver python3-selenium libjs-three
  clang libclang-rt-14-dev clang-tidy  # libFuzzer targets (tools/fuzz.sh) and tools/tidy.sh
  gcovr  # tools/coverage.sh
  postgresql libpq-dev mosquitto libmosquitto-dev  # the shop's hub and broker (src/shop/, docs/shop.md; tests start their own)
  linuxcnc-uspace  # its rs274 interpreter checks our programs (arc fitting, the complete job)
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all packages present"
fi
