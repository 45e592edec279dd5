#!/usr/bin/env bash
# Our 400:300 products against the gemm crate (stable build: its AVX2 kernels; nightly-feature
# build: its AVX-512 kernels) and matrixmultiply, one thread, alternating in one process.
#     bash benches/reference/gemm_crate/run.sh [SECONDS_PER_TIMING] [ROUNDS]
set -euo pipefail
cd "$(dirname "$0")"
target="${CARGO_TARGET_DIR:-target}"
cargo build --release --quiet
RUSTC_BOOTSTRAP=1 CARGO_TARGET_DIR="$target/avx512" cargo build --release --quiet --features avx512
echo "== gemm crate as built on stable Rust (no AVX-512 kernels) =="
"$target/release/gemm-crate-probe" "${1:-0.3}" "${2:-2}"
echo "== gemm crate with its nightly feature (AVX-512 kernels) =="
"$target/avx512/release/gemm-crate-probe" "${1:-0.3}" "${2:-2}"
