#!/usr/bin/env bash
# Installs Intel Open Image Denoise 2 (OIDN), which `caustica render --denoise` loads at run time,
# into .oidn/ under the project (git-ignored; no root needed), and prints where. Debian does not
# package OIDN; PyPI's `pyoidn` wheel (manylinux2014, x86_64) ships Intel's build of it: the
# library, its core, and its CPU and CUDA devices. Only those (and TBB, which the CPU device needs)
# are kept; the SYCL and HIP devices and their runtimes (~80 MB) are left out, and OIDN skips a
# device whose module is absent. The libraries carry RPATH $ORIGIN/../lib, so they find each other
# in .oidn/lib without LD_LIBRARY_PATH.
#
# Idempotent: a complete install of this version is left as it is. Needs python3 with pip (to
# download the wheel).
#
# Usage: scripts/install-oidn.sh [DIR]   (DIR defaults to .oidn in the project's root)
set -euo pipefail
cd "$(dirname "$0")/.."

version=2.5.1
wheel_version=2.5.1.0
wheel_sha256=32ad13368f8de1ef63001942ad05b02a00cd732d1206d97f352d3a3f606d823e
dir=${1:-.oidn}
lib="$dir/lib"
# The files caustica needs; the wheel stores its symbolic links as copies.
files=(
    libOpenImageDenoise.so.2
    "libOpenImageDenoise_core.so.$version"
    "libOpenImageDenoise_device_cpu.so.$version"
    "libOpenImageDenoise_device_cuda.so.$version"
    libtbb.so.12
)

complete() {
    [ "$(cat "$dir/VERSION" 2>/dev/null)" = "$version" ] || return 1
    for f in "${files[@]}"; do [ -f "$lib/$f" ] || return 1; done
}

if complete; then
    echo "Open Image Denoise $version is already installed in $(cd "$lib" && pwd)"
    exit 0
fi

case "$(uname -s)-$(uname -m)" in
    Linux-x86_64) ;;
    *) echo "install-oidn.sh: the pyoidn wheel is built for Linux x86_64 only, not $(uname -s) $(uname -m); install Open Image Denoise 2 from https://www.openimagedenoise.org and point CAUSTICA_OIDN at libOpenImageDenoise.so.2" >&2
       exit 1 ;;
esac

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "downloading pyoidn $wheel_version (Open Image Denoise $version) from PyPI"
python3 -m pip download --quiet --no-deps --only-binary=:all: --dest "$work" "pyoidn==$wheel_version"
wheel=$(ls "$work"/pyoidn-*.whl)
# The wheel's digest as PyPI published it (2026-12-07): a changed or corrupted download stops here.
echo "$wheel_sha256  $wheel" | sha256sum --check --quiet
python3 - "$wheel" "$work/unpacked" "${files[@]}" <<'PY'
import sys, zipfile
wheel, out, names = sys.argv[1], sys.argv[2], sys.argv[3:]
with zipfile.ZipFile(wheel) as z:
    for name in names:
        z.extract(f"pyoidn/oidn/lib/{name}", out)
PY
# Into place only once every file is there, so an interrupted install is redone, not half used.
mkdir -p "$lib"
for f in "${files[@]}"; do
    install -m 755 "$work/unpacked/pyoidn/oidn/lib/$f" "$lib/$f.partial"
    mv -f "$lib/$f.partial" "$lib/$f"
done
echo "$version" > "$dir/VERSION"
echo "installed Open Image Denoise $version in $(cd "$lib" && pwd) (caustica finds it there; or set CAUSTICA_OIDN=$(cd "$lib" && pwd)/libOpenImageDenoise.so.2)"
