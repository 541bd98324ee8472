#!/usr/bin/env bash
# Runs the whole test suite on a fresh machine: installs the software renderer the
# GUI tests draw with (Mesa's lavapipe Vulkan driver; llvmpipe GL is the fallback)
# when it is missing, checks formatting and clippy (warnings are errors), then
# `cargo test --workspace --no-fail-fast`.
set -euo pipefail
cd "$(dirname "$0")/.."

have_vulkan() { ldconfig -p 2>/dev/null | grep -q 'libvulkan.so.1' && ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1; }
if ! have_vulkan && command -v apt-get >/dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && command -v sudo >/dev/null 2>&1 && SUDO="sudo"
  echo "installing the software Vulkan driver (mesa-vulkan-drivers, libvulkan1)..."
  if ! { $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null; }; then
    echo "warning: could not install lavapipe; GUI tests fall back to llvmpipe GL" >&2
  fi
fi

# Headless: no display server is needed; wgpu renders off-screen.
unset DISPLAY WAYLAND_DISPLAY
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
chmod 700 "$XDG_RUNTIME_DIR"
export CARGO_INCREMENTAL=0 CARGO_TERM_COLOR=never

# What the README claims of the code: formatted, and clippy clean with the
# workspace lints (Cargo.toml, clippy.toml) as errors. The layering check is
# a test (tests/tests/layering.rs).
if cargo fmt --version >/dev/null 2>&1 && cargo clippy --version >/dev/null 2>&1; then
  cargo fmt --all --check
  cargo clippy --workspace --all-targets -- -D warnings
else
  echo "warning: rustfmt or clippy is not installed: format and lint checks skipped" >&2
fi
exec cargo test --workspace --no-fail-fast "$@"
