#!/usr/bin/env bash
# The cross set-up: what builds the FMUs' Windows x64 and Linux aarch64 binaries here and what
# runs them for the tests, all from Debian 12's own packages:
#   rustc-web, cargo-web, rust-web-src   (bookworm-security) a Rust compiler with the standard
#                                        library's source, so that build-fmu compiles the
#                                        standard library for each target (-Zbuild-std)
#   gcc-mingw-w64-x86-64                 the Windows linker (and objdump for the tests)
#   gcc-aarch64-linux-gnu, libc6-dev-arm64-cross   the aarch64 linker and C library
#   wine64                               runs the Windows test host (tests only)
#   qemu-user-static                     runs the aarch64 test host (tests only)
#
#   bash tests/setup_cross.sh        (both README commands run it; as root or through sudo)
#
# Nothing is installed when the machine can already do it, however it got there: the linkers
# on PATH, rustup's targets x86_64-pc-windows-gnu and aarch64-unknown-linux-gnu (or a compiler
# with the standard library's source, STEWART_BUILD_STD_RUSTC), and for the tests wine and
# qemu-aarch64 with an aarch64 C library (STEWART_AARCH64_SYSROOT). Elsewhere than Debian 12,
# install those; or build this machine's platform only: STEWART_FMU_TARGETS=x86_64-linux for
# the README commands, `cargo run --release --bin build-fmu -- --targets x86_64-linux` by hand
# (docs/platforms.md).

CROSS_BUILD_PACKAGES=(rustc-web cargo-web rust-web-src gcc-mingw-w64-x86-64 gcc-aarch64-linux-gnu libc6-dev-arm64-cross)
CROSS_TEST_PACKAGES=(wine64 qemu-user-static)

# Whether this machine can build the foreign binaries (and, for `tests`, run them).
cross_ready() {
    command -v x86_64-w64-mingw32-gcc >/dev/null && command -v aarch64-linux-gnu-gcc >/dev/null || return 1
    local rust=no
    if command -v rustup >/dev/null && rustup target list --installed 2>/dev/null | grep -q '^x86_64-pc-windows-gnu$' &&
        rustup target list --installed 2>/dev/null | grep -q '^aarch64-unknown-linux-gnu$'; then
        rust=yes
    fi
    if [ -x "${STEWART_BUILD_STD_RUSTC:-/usr/bin/rustc}" ] && [ -x "${STEWART_BUILD_STD_CARGO:-/usr/bin/cargo}" ] &&
        [ -d "$("${STEWART_BUILD_STD_RUSTC:-/usr/bin/rustc}" --print sysroot 2>/dev/null)/lib/rustlib/src/rust/library/std" ]; then
        rust=yes
    fi
    [ "$rust" = yes ] || return 1
    [ "$1" = tests ] || return 0
    { [ -x /usr/lib/wine/wine64 ] || command -v wine64 || command -v wine; } >/dev/null || return 1
    { command -v qemu-aarch64-static || command -v qemu-aarch64; } >/dev/null || return 1
    [ -e "${STEWART_AARCH64_SYSROOT:-/usr/aarch64-linux-gnu}/lib/libc.so.6" ]
}

# `cross_toolchains build` (the compilers and linkers) or `cross_toolchains tests` (also wine
# and qemu-user).
cross_toolchains() {
    local kind="${1:-tests}"
    if cross_ready "$kind"; then
        return 0
    fi
    local wanted=("${CROSS_BUILD_PACKAGES[@]}")
    [ "$kind" = tests ] && wanted+=("${CROSS_TEST_PACKAGES[@]}")
    if ! command -v apt-get >/dev/null || ! grep -q '^VERSION_CODENAME=bookworm' /etc/os-release 2>/dev/null; then
        die "the Windows and aarch64 binaries need cross toolchains: on Debian 12 this script installs them; here install rustup's targets x86_64-pc-windows-gnu and aarch64-unknown-linux-gnu, x86_64-w64-mingw32-gcc, aarch64-linux-gnu-gcc (and wine and qemu-aarch64 for the tests), or build this platform only: STEWART_FMU_TARGETS=x86_64-linux (docs/platforms.md)"
    fi
    local missing=() p
    for p in "${wanted[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    if [ ${#missing[@]} -eq 0 ]; then
        return 0
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

# Run as a command (not sourced by tests/setup.sh or a shell): the whole set-up, with the
# progress lines of tests/setup.sh.
if [[ "${BASH_SOURCE[0]}" == "$0" ]]; then
    set -euo pipefail
    cd "$(dirname "$0")/.."
    SETUP_START=$SECONDS
    step() {
        local s=$((SECONDS - SETUP_START))
        printf '[%d:%02d] %s\n' $((s / 60)) $((s % 60)) "$*"
    }
    die() {
        echo "set-up: $*" >&2
        exit 1
    }
    cross_toolchains tests
fi
