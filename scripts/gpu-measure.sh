#!/usr/bin/env bash
# caustica's speed on a GPU, in one run: the device list and `nvidia-smi`, `bench --suite` at
# 1024x768 (each scene's kernel specialized to it), smallpt's Cornell box (the anchor scene) at
# 1024x768 and 256 spp, the A/Bs the kernel has switches for (the general kernel against the
# specialized one, workgroup row order), each as `bench --json`, small renders to check by eye and
# against lavapipe's images, and, where Mitsuba 3 is at hand, `scripts/mitsuba_compare.py --variant
# cuda_ad_rgb` per scene on the same GPU. Rates come from the device's own timestamps
# (`samples_per_gpu_second`).
#
# What it needs: a built caustica (`.run/caustica`, else `target/release/caustica`; CAUSTICA=PATH
# overrides); neither cargo nor a network. A machine without the Vulkan loader needs the debs
# below unpacked. Prepare both on a machine with cargo and apt:
#   echo /.gl/ >> .git/info/exclude; echo /.run/ >> .git/info/exclude; mkdir -p .gl .run
#   (cd .gl && apt-get download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
#        # the Vulkan loader, and glvnd, without which NVIDIA's driver (libGLX_nvidia) creates no
#        # Vulkan instance: the loader then reports no driver at all
#   cargo build --release && cp target/release/caustica .run/ && strip .run/caustica
# and, optionally, in .run/ as well:
#   data.tar.xz     the shared data's meshes and maps the scenes read (tar of paths relative to
#                   ../shared/data), so the mesh scenes run too
#   mitsuba.tar.xz  Mitsuba 3 and Dr.Jit for the machine's python3, unpacked from their wheels (the
#                   variants and plugins this comparison does not use may be left out), so Mitsuba's
#                   `cuda_ad_rgb` renders the same scenes on the same GPU in the same run
# then, on the GPU machine, with .gl and .run beside the tree:
#   for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig; bash scripts/gpu-measure.sh
#
# Everything goes to $OUT (default ./gpu-out) as one archive, results.tar.gz, plus log.txt.
# SIZE=WxH and SPP shrink it for a dry run on lavapipe; MITSUBA_VARIANT=llvm_ad_rgb tries the
# comparison on a CPU; STEPS (default "caustica mitsuba") picks the parts to run: "workgroups" is the
# A/B of the kernel's workgroup shapes (CAUSTICA_WORKGROUP), the suite and the anchor scene with
# each; "queue" the A/B of the walk queue (CAUSTICA_WALK_QUEUE=1: on a GPU, with subgroup barriers)
# against the plain kernel, the suite and the anchor scene each way, and the mesh box's image with
# the queue, to check against lavapipe's; "wavefront" the same A/B of the wavefront's kernels
# (CAUSTICA_WAVEFRONT=1) against the megakernel; "tiles" the same A/B of subgroups taking their
# tiles from a counter (CAUSTICA_TAKE_TILES=1); "shaders" runs each .run/shaders-NAME/ folder
# (CAUSTICA_SHADER_DIR); "traversal" the whole matrix of the BVH walk's candidates on the suite, one
# run each (the compute walk with four- and eight-wide nodes, CAUSTICA_BVH_WIDTH; shadow rays'
# children unsorted, CAUSTICA_SHADOW_WALK; the walk queue, CAUSTICA_WALK_QUEUE; the device's ray
# queries, --traversal ray-query, where it has them; the default again, for the run's noise), and
# writes them as one table, traversal.md (scripts/traversal_table.py), and the viewer's frame rate
# and samples/s at 1280x720 under a virtual display (xvfb-run), where there is one.
set -uo pipefail
cd "$(dirname "$0")/.."
out="${OUT:-gpu-out}"
mkdir -p "$out"
results="$(mktemp -d)"
caustica="$(realpath "${CAUSTICA:-.run/caustica}" 2>/dev/null)"
[ -x "$caustica" ] || caustica="$(realpath target/release/caustica)"
size="${SIZE:-1024x768}"
width="${size%x*}"
height="${size#*x}"
spp="${SPP:-256}"
quarter=$(( spp / 4 > 0 ? spp / 4 : 1 ))
# No single measurement may hold the rest up: the device's time is short.
limit="${LIMIT_S:-150}"
if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ]; then
    export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
if [ -z "${__EGL_VENDOR_LIBRARY_FILENAMES:-}" ] && [ -f /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json ]; then
    export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
fi
if [ -f .run/data.tar.xz ]; then
    mkdir -p /tmp/caustica-data && tar -xJf .run/data.tar.xz -C /tmp/caustica-data
    export CAUSTICA_DATA=/tmp/caustica-data
fi

log() { echo "== $*" | tee -a "$results/log.txt"; }
# One measurement: NAME, then the bench arguments. A failure is logged, and the rest still run.
measure() {
    local name=$1
    shift
    log "$name: caustica bench $*"
    if ! timeout "$limit" "$caustica" bench --json "$@" >"$results/$name.json" 2>>"$results/log.txt"; then
        log "$name FAILED (exit $?)"
    fi
}
# One side of an A/B: the anchor scene and the suite, in files PREFIX-smallpt and PREFIX-suite.
measure_side() {
    measure "$1-smallpt" scenes/smallpt.toml --width "$width" --height "$height" --spp "$spp"
    measure "$1-suite" --suite --width "$width" --height "$height" --spp "$quarter"
}
# The A/B of a kernel switch: the anchor scene and the suite without it, with VAR=1 and without it
# again (the spread between the two is the run's noise), files NAME-off-*, NAME-on-*; then the mesh
# box's image with it, to check against lavapipe's.
ab_switch() {
    local name=$1 var=$2 side
    for side in off on off; do
        if [ "$side" = on ]; then export "$var"=1; else unset "$var"; fi
        measure_side "$name-$side-$SECONDS"
    done
    export "$var"=1
    render "$name-bunny-cornell-image" scenes/bunny_cornell.toml --width 256 --height 256 --spp 256 --seed 7
    unset "$var"
}
# One image: NAME, then the render arguments (small: they are checked against lavapipe's at home).
render() {
    local name=$1
    shift
    log "$name: caustica render $*"
    timeout "$limit" "$caustica" render "$@" -o "$results/$name.pfm" -q --json >"$results/$name-render.json" 2>>"$results/log.txt" || log "$name FAILED (exit $?)"
}
# One side-by-side with Mitsuba: NAME, then mitsuba_compare.py's arguments.
compare() {
    local name=$1
    shift
    log "$name: mitsuba_compare.py $*"
    timeout "$limit" python3 scripts/mitsuba_compare.py --caustica "$caustica" --variant "${MITSUBA_VARIANT:-cuda_ad_rgb}" --json --out "/tmp/compare-$name" "$@" >"$results/$name.json" 2>>"$results/log.txt" || log "$name FAILED (exit $?)"
}

log "$(date -u) $(uname -m)"
(nvidia-smi || true) >>"$results/log.txt" 2>&1
if ! "$caustica" devices 2>&1 | tee -a "$results/log.txt"; then
    # Without a device nothing below can run: say why the loader found none, and stop.
    VK_LOADER_DEBUG=error,warn,driver "$caustica" devices 2>&1 | tee -a "$results/log.txt"
    cp "$results/log.txt" "$out/log.txt"
    exit 1
fi
steps=" ${STEPS:-caustica mitsuba} "
if [[ "$steps" == *" caustica "* ]]; then
    measure smallpt scenes/smallpt.toml --width "$width" --height "$height" --spp "$spp"
    measure smallpt-in-order scenes/smallpt.toml --width "$width" --height "$height" --spp "$spp" --group-order in-order
    measure smallpt-interleaved scenes/smallpt.toml --width "$width" --height "$height" --spp "$spp" --group-order interleaved
    measure smallpt-general scenes/smallpt.toml --width "$width" --height "$height" --spp "$spp" --general-kernel
    measure suite --suite --width "$width" --height "$height" --spp "$quarter"
    measure smallpt-again scenes/smallpt.toml --width "$width" --height "$height" --spp "$spp"
    render smallpt-image scenes/smallpt.toml --width 256 --height 192 --spp 256 --seed 7
    render bunny-cornell-image scenes/bunny_cornell.toml --width 256 --height 256 --spp 256 --seed 7
fi
if [[ "$steps" == *" workgroups "* ]]; then
    # The default shape first and last: the spread between the two is the run's noise.
    for shape in default 16x8 8x16 32x4 16x4 8x4 32x2 default; do
        name=${shape/default/default-$SECONDS}
        if [ "$shape" = default ]; then unset CAUSTICA_WORKGROUP; else export CAUSTICA_WORKGROUP=$shape; fi
        measure_side "wg-$name"
    done
    unset CAUSTICA_WORKGROUP
    measure general-bunny-cornell scenes/bunny_cornell.toml --width "$width" --height "$height" --spp "$quarter" --general-kernel
fi
if [[ "$steps" == *" queue "* ]]; then
    # Scenes whose top level is not their root alone keep the plain kernel either way.
    ab_switch queue CAUSTICA_WALK_QUEUE
fi
if [[ "$steps" == *" wavefront "* ]]; then
    ab_switch wavefront CAUSTICA_WAVEFRONT
fi
if [[ "$steps" == *" tiles "* ]]; then
    # Subgroups taking their tiles from a counter (src/render/tile_taking.rs): lavapipe's default,
    # a persistent-threads loop on a GPU.
    ab_switch tiles CAUSTICA_TAKE_TILES
fi
if [[ "$steps" == *" shaders "* ]]; then
    for dir in embedded .run/shaders-*/ embedded; do
        [ -d "$dir" ] || [ "$dir" = embedded ] || continue
        name=$(basename "$dir")
        name=${name/embedded/embedded-$SECONDS}
        if [ "$dir" = embedded ]; then unset CAUSTICA_SHADER_DIR; else export CAUSTICA_SHADER_DIR=$dir; fi
        measure_side "sh-$name"
    done
    unset CAUSTICA_SHADER_DIR
fi
if [[ "$steps" == *" traversal "* ]]; then
    # Each candidate is a run-time choice of this one binary (src/render/kernel_options.rs); the
    # files trav-NAME.json become the table's columns, the default first and last.
    opt() { echo "--kernel-option $1"; }
    candidates=(
        "compute-default|--traversal compute"
        "compute-bvh8|--traversal compute $(opt bvh-width=8)"
        "compute-shadow-unsorted|--traversal compute $(opt shadow-walk=unsorted)"
        "compute-bvh8-records-storage|--traversal compute $(opt bvh-width=8) $(opt walk-records=storage)"
        "compute-queue|--traversal compute $(opt walk-queue=1)"
    )
    if "$caustica" bench --spp 1 --width 8 --height 8 --traversal ray-query >/dev/null 2>>"$results/log.txt"; then
        candidates+=("ray-query|--traversal ray-query")
    else
        log "the device has no ray queries: the table has the compute walk's candidates alone"
    fi
    candidates+=("compute-default-again|--traversal compute")
    tables=()
    for candidate in "${candidates[@]}"; do
        name=${candidate%%|*}
        # shellcheck disable=SC2086 # the options are words
        measure "trav-$name" --suite --width "$width" --height "$height" --spp "$quarter" ${candidate#*|}
        tables+=("$results/trav-$name.json")
    done
    if python3 scripts/traversal_table.py "${tables[@]}" >"$results/traversal.md" 2>>"$results/log.txt"; then
        tee -a "$results/log.txt" <"$results/traversal.md"
    else
        log "traversal table FAILED"
    fi
    # The viewer at 1280x720 on the mesh box: its frame rate and samples/s as it logs them with the
    # screenshot it was asked for (a window on a virtual display; the GPU renders, X only shows it).
    if command -v xvfb-run >/dev/null; then
        log "viewer: caustica view scenes/bunny_cornell.toml 1280x720 under xvfb-run"
        timeout "$limit" xvfb-run -a -s "-screen 0 1280x720x24" "$caustica" view scenes/bunny_cornell.toml \
            --width 1280 --height 720 --spp "$quarter" --screenshot "$results/viewer.png" 2>&1 \
            | grep -E "wrote|rror" | tee -a "$results/log.txt" || log "viewer FAILED"
    else
        log "no xvfb-run: the viewer's frame rate is left out"
    fi
fi
if [[ "$steps" == *" mitsuba "* ]]; then
    if [ -f .run/mitsuba.tar.xz ]; then
        mkdir -p /tmp/mitsuba-site && tar -xJf .run/mitsuba.tar.xz -C /tmp/mitsuba-site
        export PYTHONPATH=/tmp/mitsuba-site${PYTHONPATH:+:$PYTHONPATH}
    fi
    if python3 -c 'import mitsuba' 2>>"$results/log.txt"; then
        compare mitsuba-smallpt scenes/smallpt.toml --width "$width" --height "$height" --spp "$spp" --reference-spp $(( spp * 4 ))
        compare mitsuba-cornell scenes/cornell.toml --width "$width" --height "$height" --spp "$spp" --reference-spp $(( spp * 4 ))
        compare mitsuba-bunny-cornell scenes/bunny_cornell.toml --width "$width" --height "$height" --spp "$quarter" --reference-spp $(( quarter * 4 ))
        compare mitsuba-bunny-sky scenes/bunny_sky.toml --width "$width" --height "$height" --spp "$quarter" --reference-spp $(( quarter * 4 ))
    else
        log "no Mitsuba: the side-by-side is left out"
    fi
fi
log "done $(date -u)"
cp "$results/log.txt" "$out/log.txt"
tar -czf "$out/results.tar.gz" -C "$results" .
