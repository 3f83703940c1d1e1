#!/usr/bin/env bash
# Puts the newest Mesa lavapipe Debian has (sid's, 26.x with its own LLVM) in a folder, with sid's
# glibc and every library it needs newer than the machine's, and writes DIR/run, which starts a
# program through that folder's dynamic loader. For measurement only (docs/benchmarks/history.md, 2026-12-03, `c7edf9f`:
# how much a newer driver is worth); nothing is installed and apt's own state is not touched.
#
#   bash scripts/sid-lavapipe.sh [DIR]          # default DIR: .lavapipe-sid in the repository
#   DIR/run target/release/caustica bench ...   # caustica on that lavapipe
#
# Why a loader of its own: sid's libraries need a newer glibc than Debian 12's 2.36, so they load
# only into a process that runs on sid's glibc from its start. A program built on Debian 12 runs on
# the newer glibc unchanged. Programs it starts (a test's `caustica` subprocess) run on the
# system's loader again and do not see this driver.
set -euo pipefail
cd "$(dirname "$0")/.."
dir="$(realpath -m "${1:-.lavapipe-sid}")"
arch=x86_64-linux-gnu

rm -rf "$dir"
mkdir -p "$dir/apt/lists/partial" "$dir/apt/cache/archives/partial" "$dir/debs" "$dir/root"
# sid from the machine's own Debian mirror and keyring (its bookworm entry, deb822 or one-line, as
# scripts/current-lavapipe.sh finds it).
if [ -f /etc/apt/sources.list.d/debian.sources ]; then
    stanza=$(awk 'BEGIN { RS = "" } /Suites:[^\n]*bookworm( |\n|$)/ { print; exit }' /etc/apt/sources.list.d/debian.sources)
    mirror=$(awk '/^URIs:/ { print $2; exit }' <<<"$stanza")
    keyring=$(awk '/^Signed-By:/ { print $2; exit }' <<<"$stanza")
else
    mirror=$(grep -hE '^deb .* bookworm main' /etc/apt/sources.list | head -1 | sed -E 's/^deb (\[[^]]*\] )?([^ ]+) .*/\2/')
fi
[ -n "${mirror:-}" ] || { echo "no Debian bookworm entry in apt's sources to take the mirror from" >&2; exit 1; }
echo "deb [signed-by=${keyring:-/usr/share/keyrings/debian-archive-keyring.gpg}] $mirror sid main" > "$dir/apt/sources.list"
apt_private=(-o "Dir::Etc::sourcelist=$dir/apt/sources.list" -o Dir::Etc::sourceparts=- -o "Dir::State::Lists=$dir/apt/lists"
    -o "Dir::Cache=$dir/apt/cache" -o Debug::NoLocking=1 -o APT::Default-Release=sid)
apt-get "${apt_private[@]}" update -qq

# What installing the driver would bring or upgrade on this machine: the driver, its LLVM, glibc and
# the other libraries whose Debian 12 versions are too old. Tools, headers and debug symbols are
# left out; everything else keeps the machine's own version, which loads on the newer glibc.
packages=$(apt-get "${apt_private[@]}" -s install mesa-vulkan-drivers libvulkan1 2>/dev/null | awk '/^Inst / { print $2 }' \
    | grep -vE -- '-dev$|-dbg$|-tools$|^(make|dpkg|dpkg-dev|libdpkg-perl|locales|libc-l10n|libc-bin|libc-gconv-modules-extra|libc-dev-bin|libc-devtools|base-files|zstd)$' \
    | grep -vE '^lib(asan|tsan|lsan|ubsan|gomp|itm|quadmath|cc1|atomic)[0-9-]')
# apt-get download writes as the _apt user where it can; a root-owned folder makes it warn only.
# shellcheck disable=SC2086
(cd "$dir/debs" && apt-get "${apt_private[@]}" download -q $packages 2>&1 | grep -v 'unsandboxed' || true)
for deb in "$dir"/debs/*.deb; do dpkg-deb -x "$deb" "$dir/root"; done

loader="$dir/root/usr/lib64/ld-linux-x86-64.so.2"
[ -x "$loader" ] || { echo "no dynamic loader among sid's debs in $dir/root" >&2; exit 1; }
icd="$dir/lvp_icd.json"
# The packaged manifest names the library by its system path; point it at this copy instead.
sed "s|\"library_path\": *\"[^\"]*\"|\"library_path\": \"$dir/root/usr/lib/$arch/libvulkan_lvp.so\"|" \
    "$(ls "$dir"/root/usr/share/vulkan/icd.d/lvp_icd*.json | head -1)" > "$icd"
cat > "$dir/run" <<EOF
#!/bin/sh
# Runs a program on Debian sid's glibc and lavapipe (scripts/sid-lavapipe.sh).
export VK_DRIVER_FILES="$icd"
exec "$loader" --library-path "$dir/root/usr/lib/$arch:$dir/root/lib/$arch:/usr/lib/$arch:/lib/$arch" "\$@"
EOF
chmod +x "$dir/run"
version=$(dpkg-deb -f "$(ls "$dir"/debs/mesa-vulkan-drivers_*.deb)" Version)
echo "Mesa $version lavapipe in $dir; run a program on it with $dir/run PROGRAM ARGS" >&2
