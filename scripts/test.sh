#!/usr/bin/env bash
# Runs the whole test suite on lavapipe by default (forced even on a machine with a GPU, so every
# machine runs the same checks) with the Khronos validation layer, which fails the tests on any
# message.
#
# Which lavapipe: a current one (Mesa 24 or newer) by default. Where the system's is older (Debian
# 12 ships 22.3), scripts/current-lavapipe.sh puts Mesa 25 from bookworm-backports beside it in
# .lavapipe/ (once) and the suite runs on that. CAUSTICA_LAVAPIPE=system runs on the system's
# lavapipe whatever its version: Debian 12's 22.3 silently ends shader loops after 65,535
# iterations, a defect only it shows, which tests/sample_integrity.rs checks that caustica survives.
# An explicit VK_DRIVER_FILES wins over both.
#
# CAUSTICA_LAVAPIPE=none runs the suite on the machine's own Vulkan devices instead, so that a real
# driver is tested whenever one is at hand: no driver is forced (neither here nor by the tests'
# helpers in tests/common, which read the same variable), and every test takes the device the CLI
# takes by default (a discrete GPU, else any GPU, a CPU implementation last). The few tests that
# check what only lavapipe does say SKIPPED and why, or check the GPU's own form instead. With
# VK_DRIVER_FILES set too, that driver is the only one the loader sees.
set -euo pipefail
cd "$(dirname "$0")/.."
system_icd=/usr/share/vulkan/icd.d/lvp_icd.x86_64.json

mesa_major() {
    dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null | sed 's/^[0-9]*://; s/\..*//'
}

choice="${CAUSTICA_LAVAPIPE:-current}"
if [ "$choice" = none ]; then
    # Read by tests/common's lavapipe_override too.
    export CAUSTICA_LAVAPIPE=none
    echo "scripts/test.sh: the machine's own Vulkan devices (CAUSTICA_LAVAPIPE=none), VK_DRIVER_FILES ${VK_DRIVER_FILES:-unset}" >&2
    exec cargo test --release "$@"
fi
if [ -z "${VK_DRIVER_FILES:-}" ]; then
    case "$choice" in
    system)
        export VK_DRIVER_FILES="$system_icd"
        ;;
    current)
        major="$(mesa_major || true)"
        if [ -n "$major" ] && [ "$major" -lt 24 ]; then
            [ -f .lavapipe/env ] || bash scripts/current-lavapipe.sh .lavapipe >/dev/null
            # shellcheck disable=SC1091
            . .lavapipe/env
        else
            export VK_DRIVER_FILES="$system_icd"
        fi
        ;;
    *)
        echo "CAUSTICA_LAVAPIPE is '$choice': use 'current' (the default), 'system' or 'none' (no lavapipe forced: the machine's own devices)" >&2
        exit 1
        ;;
    esac
fi
if [ ! -f "$VK_DRIVER_FILES" ]; then
    echo "lavapipe not found at $VK_DRIVER_FILES: run 'sudo apt-get install mesa-vulkan-drivers libvulkan1 vulkan-validationlayers'" >&2
    exit 1
fi
echo "scripts/test.sh: lavapipe from $VK_DRIVER_FILES" >&2
cargo test --release "$@"

# The whole suite runs with each traversal (src/gpu/traversal.rs): the tests that trace rays
# (geometry against brute force, instancing, alpha, furnaces, images, and the specialized kernels'
# sums bit for bit against the general kernel's) again with ray queries, where
# the device has them (Mesa 24.1 or newer; tests/traversal.rs checks that Mesa 22.3 refuses them).
if [ "$#" -eq 0 ]; then
    if cargo run --release --quiet -- bench --spp 1 --width 8 --height 8 --traversal ray-query >/dev/null 2>&1; then
        echo "scripts/test.sh: the tests that trace rays again, with ray queries" >&2
        CAUSTICA_TRAVERSAL=ray-query cargo test --release \
            --test geometry --test alpha --test physics --test bias --test textures --test convergence \
            --test specialization
    else
        echo "scripts/test.sh: $VK_DRIVER_FILES has no ray queries: the compute walk alone was tested" >&2
    fi
    # The eight-wide walk (kernel option bvh-width=8, src/render/bvh_width.rs): the geometry
    # against brute force, instancing and alpha walked with eight-wide nodes, and the light tree,
    # whose index of hit emitters follows the triangles' order, which the eight-wide build changes
    # (tests/bvh_width.rs compares its images with the four-wide walk's on every checked-in scene).
    echo "scripts/test.sh: the tests that walk BVHs again, with eight-wide nodes" >&2
    CAUSTICA_BVH_WIDTH=8 cargo test --release --test geometry --test alpha --test light_tree
fi
