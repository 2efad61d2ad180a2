#!/bin/bash
# The GPU benchmarks in one run on a machine with an NVIDIA GPU and no Blender (docs/BENCHMARKS.md,
# "GPU"): the preview's passes (bench_gpu_frame.py), boxes against triangles
# (bench_gpu_triangles.py) and whether conservative depth keeps early depth under Vulkan
# (bench/vk_early_depth). Run from the repository root, with beside it, prepared on a machine
# that has Blender's bpy module and the network:
#   .gpudata/   PYTHONPATH=addon python3 -m bench.gpu_frame_data .gpudata
#   .whl/       the PyOpenGL wheel (python3 -m pip download --no-deps PyOpenGL -d .whl)
#   .gl/        Debian's GL and Vulkan loaders, if the machine has none (apt-get download libvulkan1
#               libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2), unpacked into / here
#   bench/vk_early_depth/build/   bash bench/vk_early_depth/build.sh
# Writes the tables and JSON into $OUT (default: ./gpu_out). Each bench is bounded by a timeout.
set -u
OUT=${OUT:-gpu_out}
mkdir -p "$OUT"
if [ -d .gl ]; then
    for f in .gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi
if [ -d .whl ]; then
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target /tmp/site .whl/*.whl || exit 1
    export PYTHONPATH=/tmp/site
fi
export PYTHONPATH=${PYTHONPATH:+$PYTHONPATH:}$PWD PYTHONUNBUFFERED=1
NVIDIA=/usr/local/nvidia/share
[ -f $NVIDIA/glvnd/egl_vendor.d/10_nvidia.json ] && export __EGL_VENDOR_LIBRARY_FILENAMES=$NVIDIA/glvnd/egl_vendor.d/10_nvidia.json
ICD=
for candidate in $NVIDIA/vulkan/icd.d/nvidia_icd.json /usr/share/vulkan/icd.d/nvidia_icd.json /etc/vulkan/icd.d/nvidia_icd.json; do
    [ -z "$ICD" ] && [ -f "$candidate" ] && ICD=$candidate
done
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm,pstate --format=csv 2>&1 | tee "$OUT/gpu.txt"

VK=bench/vk_early_depth/build
if [ -x $VK/vk_early_depth ] && [ -n "$ICD" ]; then
    VK_DRIVER_FILES=$ICD VK_ICD_FILENAMES=$ICD timeout 90 $VK/vk_early_depth --json "$OUT/vk_early_depth.json" \
        > "$OUT/vk_early_depth.txt" 2>&1
    echo "vk_early_depth: rc=$?"
else
    echo "vk_early_depth: not run (no build or no NVIDIA Vulkan ICD)"
fi
timeout 300 python3 -m bench.bench_gpu_frame .gpudata --naive-sizes "" --json "$OUT/gpu_frame.json" \
    > "$OUT/gpu_frame.txt" 2>&1
echo "bench_gpu_frame: rc=$?"
timeout 200 python3 -m bench.bench_gpu_triangles .gpudata/chains --json "$OUT/gpu_triangles.json" \
    > "$OUT/gpu_triangles.txt" 2>&1
echo "bench_gpu_triangles: rc=$?"
nvidia-smi --query-gpu=clocks.sm,pstate --format=csv,noheader 2>&1 | tee -a "$OUT/gpu.txt"
tail -n 40 "$OUT"/*.txt
