#!/usr/bin/env bash
# Puts a current Mesa lavapipe (25.x, Vulkan 1.4) beside the system's, without replacing anything:
# Debian 12 ships Mesa 22.3, whose lavapipe runs caustica's kernel about 3x slower and silently ends
# shader loops after 65,535 iterations (caustica works around that, see docs/testing.md).
#
#   bash scripts/current-lavapipe.sh [DIR]     # default DIR: .lavapipe in the repository
#
# Debian 12: the debs come from bookworm-backports, which is added to apt's sources (derived from
# the machine's own bookworm entry, so its mirror is kept) when it is missing. Ubuntu 24.04 and
# newer already ship Mesa 24+: `apt-get install mesa-vulkan-drivers` is enough there, and this
# script says so. On success it prints the two variables to export; scripts/test.sh uses DIR/env by
# itself when CAUSTICA_LAVAPIPE=current.
set -euo pipefail
cd "$(dirname "$0")/.."
dir="$(realpath -m "${1:-.lavapipe}")"
sudo=$(command -v sudo || true)
[ "$(id -u)" = 0 ] && sudo=

. /etc/os-release
if [ "${ID:-}" = ubuntu ]; then
    echo "Ubuntu ${VERSION_ID:-}: its own mesa-vulkan-drivers is current from 24.04 on; install that instead." >&2
    exit 1
fi
if [ "${VERSION_CODENAME:-}" != bookworm ]; then
    echo "this script knows Debian 12 (bookworm); on ${PRETTY_NAME:-this system} install the distribution's mesa-vulkan-drivers (Mesa 24 or newer)" >&2
    exit 1
fi

backports=/etc/apt/sources.list.d/caustica-bookworm-backports.sources
if ! apt-cache policy mesa-vulkan-drivers 2>/dev/null | grep -q 'bpo12'; then
    if ! grep -rqs 'bookworm-backports' /etc/apt/sources.list /etc/apt/sources.list.d/; then
        # Copy the stanza that carries bookworm itself (deb822 or one-line format) and point it at
        # bookworm-backports, keeping the machine's mirror and keyring.
        if [ -f /etc/apt/sources.list.d/debian.sources ]; then
            awk 'BEGIN { RS = ""; ORS = "\n\n" } /Suites:[^\n]*bookworm( |\n|$)/ { print; exit }' /etc/apt/sources.list.d/debian.sources \
                | sed 's/^Suites: .*/Suites: bookworm-backports/' | $sudo tee "$backports" >/dev/null
        else
            grep -hE '^deb .* bookworm main' /etc/apt/sources.list | head -1 | sed 's/ bookworm main.*/ bookworm-backports main/' \
                | $sudo tee "${backports%.sources}.list" >/dev/null
        fi
    fi
    $sudo apt-get update -qq
fi

version=$(apt-cache policy mesa-vulkan-drivers | awk '/bpo12/ && $1 ~ /^[0-9]/ { print $1; exit } /bpo12/ && $2 ~ /^[0-9]/ { print $2; exit }')
if [ -z "$version" ]; then
    echo "no backported mesa-vulkan-drivers found in apt's lists" >&2
    exit 1
fi
drm=$(apt-cache policy libdrm2 | awk '/bpo12/ && $1 ~ /^[0-9]/ { print $1; exit } /bpo12/ && $2 ~ /^[0-9]/ { print $2; exit }')

rm -rf "$dir"
mkdir -p "$dir/debs" "$dir/root"
# apt-get download writes as the _apt user where it can; a root-owned folder makes it warn only.
(cd "$dir/debs" && apt-get download -q "mesa-vulkan-drivers=$version" "libdrm2=$drm" "libdrm-amdgpu1=$drm" 2>&1 | grep -v 'unsandboxed' || true)
for deb in "$dir"/debs/*.deb; do dpkg-deb -x "$deb" "$dir/root"; done

lib="$dir/root/usr/lib/x86_64-linux-gnu"
icd="$dir/lvp_icd.json"
# The packaged manifest names the library by its system path; point it at this copy instead.
sed "s|\"library_path\": *\"[^\"]*\"|\"library_path\": \"$lib/libvulkan_lvp.so\"|" \
    "$(ls "$dir"/root/usr/share/vulkan/icd.d/lvp_icd*.json | head -1)" > "$icd"
cat > "$dir/env" <<EOF
export VK_DRIVER_FILES="$icd"
export LD_LIBRARY_PATH="$lib\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}"
EOF
echo "Mesa $version lavapipe in $dir; to use it:" >&2
echo "  . $dir/env" >&2
cat "$dir/env"
