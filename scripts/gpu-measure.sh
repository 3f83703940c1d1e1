#!/usr/bin/env bash
# The speed issue's GPU measurements in one run, for a session that is lent a GPU machine for a
# few minutes (no cargo, no network there). Prepare here:
#   echo /.gl/ >> .git/info/exclude; echo /.run/ >> .git/info/exclude; mkdir -p .gl .run
#   (cd .gl && apt-get download libvulkan1)        # the Vulkan loader, which the machine lacks
#   cargo build --release && cp target/release/caustica .run/
# then run there, carrying .gl and .run:
#   for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; bash scripts/gpu-measure.sh
# Everything goes to $OUT (default ./gpu-out): the device list, the suite at 1024x768 (the issue's
# size), the smallpt anchor scene at 1024x768, 256 spp, and the A/Bs the kernel has switches for
# (general kernel, workgroup row order), each as `bench --json`. Rates come from the device's own
# timestamps (`samples_per_gpu_second`). SIZE=WxH and SPP shrink it for a dry run on lavapipe.
set -uo pipefail
cd "$(dirname "$0")/.."
out="${OUT:-gpu-out}"
mkdir -p "$out"
caustica="${CAUSTICA:-.run/caustica}"
[ -x "$caustica" ] || caustica=target/release/caustica
size="${SIZE:-1024x768}"
width="${size%x*}"
height="${size#*x}"
spp="${SPP:-256}"
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]; then
    export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi

log() { echo "== $*" | tee -a "$out/log.txt"; }
# One measurement: NAME, then the bench arguments. A failure is logged, and the rest still run.
measure() {
    local name=$1
    shift
    log "$name: caustica bench $*"
    if ! "$caustica" bench --json "$@" >"$out/$name.json" 2>>"$out/log.txt"; then
        log "$name FAILED (exit $?)"
    fi
}

log "$(date -u) $(uname -m)"
"$caustica" devices 2>&1 | tee -a "$out/log.txt"
measure smallpt scenes/smallpt.toml --width "$width" --height "$height" --spp "$spp"
measure smallpt-in-order scenes/smallpt.toml --width "$width" --height "$height" --spp "$spp" --group-order in-order
measure smallpt-interleaved scenes/smallpt.toml --width "$width" --height "$height" --spp "$spp" --group-order interleaved
measure smallpt-general scenes/smallpt.toml --width "$width" --height "$height" --spp "$spp" --general-kernel
measure suite --suite --width "$width" --height "$height" --spp "$(( spp / 4 > 0 ? spp / 4 : 1 ))"
log "done $(date -u)"
