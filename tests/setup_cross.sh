#!/usr/bin/env bash
# The cross set-up: what builds the FMUs' Windows x64 and Linux aarch64 binaries here and what
# runs them for the tests, all from Debian 12's own packages:
#   rustc-web, cargo-web, rust-web-src   (bookworm-security) a Rust compiler with the standard
#                                        library's source, so that build-fmu compiles the
#                                        standard library for each target (-Zbuild-std)
#   gcc-mingw-w64-x86-64                 the Windows linker (and objdump for the tests)
#   gcc-aarch64-linux-gnu, libc6-dev-arm64-cross   the aarch64 linker and C library
#   wine64                               runs the Windows test host
#   qemu-user-static                     runs the aarch64 test host
#
#   bash tests/setup_cross.sh        (both README commands run it; as root or through sudo)
#
# Elsewhere (another distribution, or rustup that can fetch targets): `rustup target add
# x86_64-pc-windows-gnu aarch64-unknown-linux-gnu`, a MinGW-w64 and an aarch64 GNU/Linux
# cross gcc on PATH (x86_64-w64-mingw32-gcc, aarch64-linux-gnu-gcc), wine and qemu-aarch64
# for the tests; or build this machine's platform only: `cargo run --release --bin build-fmu
# -- --targets x86_64-linux` (docs/platforms.md).

CROSS_PACKAGES=(rustc-web cargo-web rust-web-src gcc-mingw-w64-x86-64 gcc-aarch64-linux-gnu libc6-dev-arm64-cross
                wine64 qemu-user-static)

cross_toolchains() {
    local missing=()
    local p
    for p in "${CROSS_PACKAGES[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if [ ${#missing[@]} -eq 0 ]; then
        return 0
    fi
    if ! command -v apt-get >/dev/null || ! grep -q '^VERSION_CODENAME=bookworm' /etc/os-release 2>/dev/null; then
        die "the cross toolchains come from Debian 12 (bookworm) here; on this system install rustup's targets x86_64-pc-windows-gnu and aarch64-unknown-linux-gnu, x86_64-w64-mingw32-gcc, aarch64-linux-gnu-gcc, wine and qemu-aarch64, or build this platform only: cargo run --release --bin build-fmu -- --targets x86_64-linux (docs/platforms.md)"
    fi
    local sudo=""
    if [ "$(id -u)" -ne 0 ]; then
        command -v sudo >/dev/null || die "missing ${missing[*]}: install them as root: apt-get install --no-install-recommends ${missing[*]}"
        sudo="sudo"
    fi
    step "the cross toolchains: updating Debian's package lists"
    $sudo apt-get update -qq
    local candidate
    candidate=$(apt-cache policy rustc-web 2>/dev/null | awk '/Candidate:/{print $2}')
    if [ -z "$candidate" ] || [ "$candidate" = "(none)" ]; then
        die "rustc-web is not available: add Debian's security suite (deb http://deb.debian.org/debian-security bookworm-security main) to the apt sources"
    fi
    # apt's own figures for what it is about to fetch and unpack (it stops at the question).
    local sizes
    sizes=$( (LC_ALL=C $sudo apt-get install --no-install-recommends --assume-no "${missing[@]}" 2>/dev/null || true) |
        sed -n -e 's/^Need to get \([^ ]* [^ ]*\) of archives.*/\1 to download/p' \
               -e 's/^After this operation, \([^ ]* [^ ]*\) of additional disk space.*/\1 on disk/p' | paste -sd, - | sed 's/,/, /')
    step "installing the cross toolchains from Debian 12 (${missing[*]}; rustc-web $candidate): ${sizes:-size unknown}, one to three minutes"
    $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
    step "the cross toolchains are installed"
}

# Run directly (not sourced by tests/setup.sh): the set-up alone.
if [ "${#BASH_SOURCE[@]}" -eq 1 ]; then
    set -euo pipefail
    cd "$(dirname "$0")/.."
    source tests/setup.sh
    cross_toolchains
fi
