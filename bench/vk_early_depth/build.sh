#!/usr/bin/env bash
# Builds the Vulkan early-depth harness (vk_early_depth.cpp: what it measures, how to run it) and
# its SPIR-V into OUT (default: bench/vk_early_depth/build/, ignored by git). Needs g++,
# glslangValidator (glslang-tools) and the Vulkan headers and loader (libvulkan-dev).
# Usage: bash bench/vk_early_depth/build.sh [OUT]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="${1:-$here/build}"
mkdir -p "$out"

# compile STAGE OUTPUT DEFINE SOURCE (DEFINE may be empty): glslangValidator prints its errors on
# stdout, shown only on failure.
compile() {
  local log
  if ! log="$(glslangValidator -V -S "$1" ${3:+"-D$3"} -o "$out/$2" "$here/$4")"; then
    echo "$log" >&2
    exit 1
  fi
}
compile vert layers.vert.spv "" layers.vert.glsl
for variant in no_depth_write depth_undeclared depth_greater depth_unchanged early_fragment_tests; do
  compile frag "$variant.frag.spv" "VARIANT_${variant^^}" layer.frag.glsl
done
# Static libstdc++ and libgcc, and the Vulkan loader copied beside the binary (found there first
# through the $ORIGIN run path): OUT runs as it is on another x86-64 Linux with glibc 2.36 or later
# and a Vulkan driver, with or without a loader of its own. The Vulkan structures are zero-filled
# by naming only their sType: the warning about the rest is off.
# shellcheck disable=SC2016  # '$ORIGIN' is for the dynamic linker, not the shell
g++ -std=c++17 -O2 -Wall -Wextra -Wno-missing-field-initializers -static-libstdc++ -static-libgcc \
    -Wl,-rpath,'$ORIGIN' -o "$out/vk_early_depth" "$here/vk_early_depth.cpp" -lvulkan
cp -L "$(g++ -print-file-name=libvulkan.so.1)" "$out/libvulkan.so.1"
