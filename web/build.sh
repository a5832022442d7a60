#!/usr/bin/env bash
# Builds the browser trainer into web/pkg (serve web/ with web/serve.sh). Installs what it needs from
# the registries: the wasm32 target (rustup) and wasm-bindgen-cli at the version Cargo.lock pins.
set -euo pipefail
cd "$(dirname "$0")/.."
rustup target list --installed | grep -qx wasm32-unknown-unknown || rustup target add wasm32-unknown-unknown
version=$(grep -A1 '^name = "wasm-bindgen"$' Cargo.lock | sed -n 's/^version = "\(.*\)"$/\1/p')
if ! wasm-bindgen --version 2>/dev/null | grep -qF "$version"; then
  # --locked takes the tool's own lock file; a registry mirror may lack one of its pinned versions (seen:
  # webpki-roots 1.0.11 of wasm-bindgen-cli 0.2.130's lock), and then the tool's requirements are
  # resolved afresh. The version of wasm-bindgen-cli itself stays the one Cargo.lock pins.
  cargo install wasm-bindgen-cli --version "$version" --locked ||
    { echo "web/build.sh: wasm-bindgen-cli's locked dependencies are not all in the registry; resolving them afresh" >&2
      cargo install wasm-bindgen-cli --version "$version"; }
fi
# WebAssembly SIMD (every browser since 2021): the engine's loops vectorise; the careful meninges script's
# steps 219 -> 160 us in headless Chromium at 128 x 96, with the same results.
RUSTFLAGS="${RUSTFLAGS:-} -C target-feature=+simd128" cargo build --release --target wasm32-unknown-unknown --bin dissect-web
target=${CARGO_TARGET_DIR:-target}
wasm-bindgen --target web --no-typescript --out-dir web/pkg --out-name dissect \
  "$target/wasm32-unknown-unknown/release/dissect-web.wasm"
gzip -9 -k -f web/pkg/dissect_bg.wasm
echo "web/pkg: $(stat -c %s web/pkg/dissect_bg.wasm) bytes of wasm, $(stat -c %s web/pkg/dissect_bg.wasm.gz) compressed"
