#!/usr/bin/env bash
# One entry point for people and CI: installs what is missing (Debian packages, only when
# missing), configures, builds, then runs the chosen job.
#   toolchain/build.sh demo   build and run the main job on embedded defaults
#   toolchain/build.sh test   build and run the whole test suite (what CI runs)
set -euo pipefail
cd "$(dirname "$0")/.."

job=${1:-}
case "$job" in
  demo|test) ;;
  *) echo "usage: toolchain/build.sh demo|test" >&2; exit 2 ;;
esac

# Debian packages: the host build, then what only the tests need (cross compilers for the
# microcontroller build of the core). The host preset configures the tests too, so their own
# libraries are here (libfftw3-dev: the analyzer's PSD and the power-law noise of tests/support;
# pybind11 and pytest: the Python package host_tools/python and its tests; libjs-chart.js: the live
# page's plotting library, compiled into the decoder and the demo at build time).
packages=(
  g++ cmake ninja-build pkg-config
  libgtest-dev libgmock-dev libbenchmark-dev libfftw3-dev
  libboost-dev libcli11-dev libfmt-dev nlohmann-json3-dev zlib1g-dev libplplot-dev plplot-driver-cairo
  libgpiod-dev libjs-chart.js
  python3-dev python3-numpy pybind11-dev python3-pybind11 python3-pytest
)
if [ "$job" = test ]; then
  # The board (aarch64, tests under qemu-aarch64-static) needs Debian's arm64 multiarch packages.
  if ! dpkg --print-foreign-architectures | grep -qx arm64; then
    sudo_cmd=(); [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
    "${sudo_cmd[@]}" dpkg --add-architecture arm64
  fi
  packages+=(g++-aarch64-linux-gnu qemu-user-static libgtest-dev:arm64 libgpiod-dev:arm64)
  packages+=(gcc-arm-none-eabi libstdc++-arm-none-eabi-newlib libnewlib-arm-none-eabi
             python3-canmatrix python3-can clang libclang-rt-14-dev)
  packages+=(python3-scipy)  # the allantools peer the Python tests compare with, when it is beside the checkout
  packages+=(python3-pandas python3-matplotlib)  # the Python package's to_pandas() and plot(), tested
  packages+=(python3-venv)  # python.install: the package installed by pip into a venv
  packages+=(chromium)  # tests labelled browser: the HTML reports and the live page rendered headless (DOM, screenshot)
  # The QEMU bench (toolchain/bench/build.sh adds the kernel headers of the kernel it boots).
  packages+=(qemu-system-x86 busybox-static cpio can-utils)
  packages+=(clang-format)  # toolchain/format.sh: the sources' style (.clang-format)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "build.sh: installing missing Debian packages: ${missing[*]}" >&2
  sudo_cmd=(); [ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# Each stage's banner gives the time since the start, so a slow stage shows in the CI log.
stage() { echo "build.sh: [$((SECONDS / 60)) min $((SECONDS % 60)) s] $*" >&2; }
if [ "$job" = test ]; then
  # First and cheap (seconds, no build): CI fails on sources not in the style of .clang-format.
  stage "the sources' format (toolchain/format.sh --check)"
  toolchain/format.sh --check
fi

cmake --preset host >/dev/null
cmake --build --preset host -j "$(nproc)"

case "$job" in
  demo)
    # The main job: the live system as a host simulation on a virtual clock. Two simulated ring
    # laser gyros (1 arcsec pulses at 100 Hz) feed the board program's own loop through the HAL
    # fakes, their reports cross an in-process CAN bus that loses 1 frame in 2000, and the decoder
    # shows what arrives and leaves a CSV and the ADEV/MDEV plot behind.
    mkdir -p build/demo
    build/host/host_tools/gyrochar-demo --hours 6 --nodes 2 --loss 0.0005 --view-every 60 \
      --csv build/demo/decoded.csv --plot build/demo/adev
    ;;
  test)
    # Every configuration is built once; the host suite runs last so that its summary closes the log.
    for mcu in cortex-m4 cortex-m7; do
      stage "freestanding core for $mcu (text/data/bss of the MCU example):"
      cmake --preset "$mcu" >/dev/null
      cmake --build --preset "$mcu" >/dev/null
      arm-none-eabi-size "build/$mcu/firmware/mcu/gyrochar-mcu-example" >&2
    done
    stage "fuzz targets, smoke run"
    cmake --preset fuzz >/dev/null
    cmake --build --preset fuzz -j "$(nproc)"
    tests/fuzz/run.sh 10
    stage "the board build (aarch64): tests under qemu-aarch64-static, install into a staging root"
    cmake --preset aarch64 >/dev/null
    cmake --build --preset aarch64 -j "$(nproc)"
    ctest --preset aarch64 -j "$(nproc)"
    DESTDIR="$PWD/build/aarch64/staging" cmake --install build/aarch64 >/dev/null
    find build/aarch64/staging -type f | sed 's|^build/aarch64/staging|build.sh: staged |' >&2
    stage "the test suite under AddressSanitizer and UndefinedBehaviorSanitizer"
    cmake --preset sanitize >/dev/null
    cmake --build --preset sanitize -j "$(nproc)"
    ctest --preset sanitize -j "$(nproc)"
    stage "the QEMU bench: a real kernel's CAN and GPIO drivers under emulation (docs/bench.md)"
    toolchain/bench/build.sh
    # A scenario whose edges the emulator stalled past an interval's end cannot be judged (docs/bench.md,
    # "GPIO timing"); a failed scenario runs once more, and fails CI only if it fails twice.
    ctest --preset host -L bench -j "$(nproc)" --repeat until-pass:2
    stage "the host test suite"
    ctest --preset host -j "$(nproc)" -LE bench
    stage "done"
    ;;
esac
