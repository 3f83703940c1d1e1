#!/usr/bin/env bash
# Runs the whole test suite on lavapipe (forced even on a machine with a GPU, so every machine runs
# the same checks) with the Khronos validation layer, which fails the tests on any message.
set -euo pipefail
cd "$(dirname "$0")/.."
export VK_DRIVER_FILES="${VK_DRIVER_FILES:-/usr/share/vulkan/icd.d/lvp_icd.x86_64.json}"
if [ ! -f "$VK_DRIVER_FILES" ]; then
    echo "lavapipe not found at $VK_DRIVER_FILES: run 'sudo apt-get install mesa-vulkan-drivers libvulkan1 vulkan-validationlayers'" >&2
    exit 1
fi
cargo test --release "$@"
