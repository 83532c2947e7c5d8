#!/usr/bin/env bash
# Fetches Intel Open Image Denoise (OIDN), which `rt-view render --denoise`
# and the viewer's Denoise toggle load at run time, into a cache folder.
#
#   scripts/get_oidn.sh [DIR]
#
# DIR defaults to $RT_VIEW_OIDN, else ~/.cache/rt-view/oidn; the libraries go
# to DIR/lib (their RPATH is $ORIGIN/../lib, so the folder must be called
# lib). OIDN is not in Debian's packages; the PyPI wheel `pyoidn` ships the
# library, its CPU device and TBB. The wheel is fetched with pip (which honours
# the machine's index settings) and only the CPU libraries are extracted
# (about 70 MB; the CUDA, HIP and SYCL devices are left out). Nothing is
# installed into any Python environment. Running it again replaces the folder.
set -euo pipefail
version=2.5.1
dir=${1:-${RT_VIEW_OIDN:-$HOME/.cache/rt-view/oidn}}
download=$(mktemp -d)
trap 'rm -rf "$download"' EXIT
python3 -m pip download --quiet --no-deps --only-binary=:all: "pyoidn==$version" -d "$download"
wheel=$(ls "$download"/pyoidn-*.whl)
mkdir -p "$dir"
rm -rf "$dir/lib.new"
python3 - "$wheel" "$dir/lib.new" <<'PY'
import os, shutil, sys, zipfile
wheel, out = sys.argv[1], sys.argv[2]
os.makedirs(out)
skip = ("cuda", "hip", "sycl", "ur_", "umf")
with zipfile.ZipFile(wheel) as z:
    for name in z.namelist():
        base = os.path.basename(name)
        if name.startswith("pyoidn/oidn/lib/") and ".so" in base and not any(s in base for s in skip):
            with z.open(name) as src, open(os.path.join(out, base), "wb") as dst:
                shutil.copyfileobj(src, dst)
PY
# Swap the new folder in whole: a run cut short leaves the old one working.
rm -rf "$dir/lib.old"
[[ -d "$dir/lib" ]] && mv "$dir/lib" "$dir/lib.old"
mv "$dir/lib.new" "$dir/lib"
rm -rf "$dir/lib.old"
echo "OIDN $version in $dir/lib"
