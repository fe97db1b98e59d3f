#!/bin/sh
# Build an FMI 2.0 or 3.0 co-simulation FMU for Linux x86-64 from a folder of C sources and its modelDescription.xml:
#
#   examples/fmu/build.sh SRC_DIR OUT.fmu
#
# compiles SRC_DIR/*.c with the system C compiler (`cc`, or $CC; common/ beside this script, the example FMUs' shared
# FMI 2.0 glue, on its include path) into binaries/linux64/<modelIdentifier>.so (FMI 3.0:
# binaries/x86_64-linux/), adds SRC_DIR/modelDescription.xml (and SRC_DIR/resources/, if there is one) and packs them into OUT.fmu with Python's zipfile module
# (no `zip` needed). The FMI headers come from $FMI_HEADERS (a folder holding fmi2Functions.h and fmi3Functions.h), else from the fmpy package that
# `python3` ($PYTHON) imports (pip install fmpy). Everything happens in a temporary folder: OUT.fmu appears whole or
# not at all.
set -eu

die() {
    echo "build.sh: $*" >&2
    exit 1
}

[ "$#" -eq 2 ] || die "usage: build.sh SRC_DIR OUT.fmu"
src=$1
out=$2
python=${PYTHON:-python3}
compiler=${CC:-cc}

[ -d "$src" ] || die "$src is not a folder"
[ -f "$src/modelDescription.xml" ] || die "$src has no modelDescription.xml"
set -- "$src"/*.c
[ -f "$1" ] || die "$src has no .c file"
case $out in
*.fmu) ;;
*) die "$out: the FMU's name must end in .fmu" ;;
esac
command -v "$python" >/dev/null 2>&1 || die "$python not found: it packs the FMU (set PYTHON to another Python 3)"
case $python in
/*) ;;
*/*) python=$PWD/$python ;; # a relative path: it also runs from inside the temporary folder
esac
command -v "$compiler" >/dev/null 2>&1 || die "C compiler $compiler not found (Debian: apt-get install gcc; or set CC)"

# The binary's name, the modelIdentifier of <CoSimulation>, and its folder, which the FMI version decides (this also
# checks that the XML is well-formed).
found=$("$python" -c '
import sys, xml.etree.ElementTree as ET
root = ET.parse(sys.argv[1]).getroot()
cs = root.find("CoSimulation")
folders = {"2.0": "linux64", "3.0": "x86_64-linux"}
if root.get("fmiVersion") not in folders or cs is None or not cs.get("modelIdentifier"):
    sys.exit(sys.argv[1] + ": not an FMI 2.0 or 3.0 co-simulation model description with a modelIdentifier")
print(cs.get("modelIdentifier"), folders[root.get("fmiVersion")], root.get("fmiVersion"))
' "$src/modelDescription.xml") || die "cannot read the modelIdentifier from $src/modelDescription.xml"
id=${found%% *}
rest=${found#* }
platform=${rest%% *}
version=${rest#* }

if [ -z "${FMI_HEADERS:-}" ]; then
    FMI_HEADERS=$("$python" -c 'import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), "c-code"))' 2>/dev/null) ||
        die "no FMI headers: set FMI_HEADERS to a folder with fmi2Functions.h, or pip install fmpy for $python"
fi
header=fmi${version%%.*}Functions.h
[ -f "$FMI_HEADERS/$header" ] || die "$FMI_HEADERS has no $header (FMI_HEADERS must hold the FMI $version headers)"

# The FMI 2.0 glue the example FMUs share (fmi2_glue.h), beside this script: on the include path of every build.
glue=$(cd "$(dirname "$0")/common" && pwd) || die "the folder common/ beside build.sh is missing (it holds fmi2_glue.h)"

tmp=$(mktemp -d "${TMPDIR:-/tmp}/fmu-build.XXXXXX") || die "cannot create a temporary folder"
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' HUP INT TERM
mkdir -p "$tmp/fmu/binaries/$platform"

"$compiler" -shared -fPIC -O2 -Wall -I "$FMI_HEADERS" -I "$glue" -o "$tmp/fmu/binaries/$platform/$id.so" "$@" -lm ||
    die "compiling $* failed"
cp "$src/modelDescription.xml" "$tmp/fmu/modelDescription.xml"
set -- modelDescription.xml binaries
if [ -d "$src/resources" ]; then
    cp -R "$src/resources" "$tmp/fmu/resources"
    set -- "$@" resources
fi
(cd "$tmp/fmu" && "$python" -m zipfile -c "$tmp/packed.fmu" "$@") ||
    die "packing $out failed"
# Copied beside OUT first and renamed into place: a reader never sees half an FMU, even across file systems.
partial="$out.partial.$$"
if ! cp "$tmp/packed.fmu" "$partial" || ! mv -f "$partial" "$out"; then
    rm -f "$partial"
    die "cannot write $out"
fi
echo "build.sh: $out ($id, FMI $version co-simulation, binaries/$platform/$id.so)"
