#!/usr/bin/env bash
# The whole GPU bench in one command, on whatever machine has the GPU: builds trompe, names the
# adapter, runs `trompe bench gpu` (every method with a GPU path beside the CPU on every
# reflection scene; trace and impostor frames against output resolution up to 1920 × 1080, the
# impostor frame against impostor resolution; the impostor walk beside the BVH on the same
# reflected rays as the mesh grows 16×; impostor construction; the exact ray query), and writes
# everything to one file (default: bench/gpu-results.txt).
#
#   bench/gpu.sh [OUTPUT_FILE]
#
# It needs a Vulkan, Metal or DX12 driver (on Linux, the Vulkan loader libvulkan1 and the GPU's
# ICD) and ../shared beside the checkout for the scenes' meshes and panoramas. On a machine
# without a GPU it runs on Mesa's lavapipe and says so in every heading. Takes a few minutes.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-bench/gpu-results.txt}
cargo build --release --quiet
{
  echo "# trompe bench gpu, $(date -u +%Y-%m-%dT%H:%MZ), commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
  echo "## trompe info --gpu"
  target/release/trompe info --gpu
  echo "## trompe bench gpu"
  target/release/trompe bench gpu
} 2>&1 | grep -v 'XDG_RUNTIME_DIR' | tee "$out"
echo "wrote $out" >&2
