# Set-up shared by the two README commands (examples/main_job.sh and tests/run_all.sh), sourced
# by both: the prerequisites checked and, on Debian, installed without their recommends; the
# Python environment in .venv; a progress line before every step that takes more than a few
# seconds, with the time since the command started.

SETUP_START=$SECONDS

# A progress line: "[m:ss] what is done now".
step() {
    local s=$((SECONDS - SETUP_START))
    printf '[%d:%02d] %s\n' $((s / 60)) $((s % 60)) "$*"
}

die() {
    echo "set-up: $*" >&2
    exit 1
}

# `in_background NAME COMMAND...`: runs a step beside the others, its output into
# target/test-logs/NAME.log; `finish NAME` waits for it and, if it failed, shows its log's end.
declare -A BACKGROUND
in_background() {
    local name="$1"
    shift
    mkdir -p target/test-logs
    ("$@") > "target/test-logs/$name.log" 2>&1 &
    BACKGROUND[$name]=$!
}
finish() {
    if ! wait "${BACKGROUND[$1]}"; then
        tail -n 40 "target/test-logs/$1.log" >&2
        die "$1 failed (its whole output: target/test-logs/$1.log)"
    fi
}

# Debian packages for what is missing; elsewhere, a message naming what to install.
apt_install() {
    local sudo=""
    if ! command -v apt-get >/dev/null; then
        die "missing: $* (Debian package names); this is not a Debian system: install them with your package manager"
    fi
    if [ "$(id -u)" -ne 0 ]; then
        command -v sudo >/dev/null || die "missing: $*: install them as root: apt-get install --no-install-recommends $*"
        sudo="sudo"
    fi
    step "installing $* from Debian's packages (without their recommends; a minute or two)"
    $sudo apt-get update -qq
    $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$@" >/dev/null
}

# `check_disk KIND`: a warning, with the numbers, where the repository's file system has less
# free space than KIND takes on a fresh machine, so that a run that then fails with "No space
# left on device" has its cause on its first lines. The full tier added 10.4 GB to a fresh
# Debian 12 machine at its largest, at its end (measured 2026-12-02, df every 5 s): the cross
# toolchains 2.6 GB, the arm64 Python root 1.0, the Wine prefix 0.7, the rest of target/ 2.0,
# .venv 0.8, the crates 0.45, fmi-sim's build and the tests' files in /tmp the rest. The main
# job and the quick tier need less (6 and 3 GB: estimates from those parts, not measured). A
# machine that has the toolchains and builds already needs far less: a warning, not a stop.
check_disk() {
    local need_gb
    case "$1" in
        tests) need_gb=11 ;;
        main) need_gb=6 ;;
        *) need_gb=3 ;;
    esac
    local free_kb
    # The repository's file system (the builds, .venv and, on a machine of one disk as CI's,
    # the toolchains too); a df that cannot tell skips the check.
    free_kb=$(df -Pk . 2>/dev/null | awk 'NR == 2 {print $4}') || return 0
    [ -n "$free_kb" ] || return 0
    if [ "$free_kb" -lt $((need_gb * 1024 * 1024)) ]; then
        step "warning: $(awk -v k="$free_kb" 'BEGIN {printf "%.1f", k / 1048576}') GB free on the repository's file system; on a fresh machine this command needs about $need_gb GB (toolchains, builds, .venv); it may stop with 'No space left on device'"
    fi
}

# `require main` (the main job), `require tests` (the tests' full tier: also gcc, valgrind,
# libclang, Chromium) or `require quick` (their quick tier: no Node.js, valgrind, libclang or
# Chromium). Rust is not a Debian package here: rustup installs it.
require() {
    SETUP_KIND="$1"  # what cross_toolchains installs: the linkers, and for the tests wine and qemu
    local need=()
    command -v cargo >/dev/null || die "cargo is not installed: install Rust 1.95 or newer (the FMU crate uses std::hint::cold_path) with rustup (https://rustup.rs), then open a new shell"
    local rust
    rust=$(rustc --version | awk '{print $2}')
    if ! printf '1.95.0\n%s\n' "$rust" | sort -V -C; then
        die "rustc $rust is too old: 1.95 or newer is needed (std::hint::cold_path): rustup update"
    fi
    command -v python3 >/dev/null || need+=(python3)
    if command -v python3 >/dev/null; then
        python3 -c 'import sys; sys.exit(sys.version_info < (3, 11))' ||
            die "python3 is $(python3 --version 2>&1 | cut -d' ' -f2): 3.11 or newer is needed"
        python3 -c 'import ensurepip, venv' 2>/dev/null || need+=(python3-venv)
    fi
    command -v cc >/dev/null || need+=(gcc)  # cargo's linker
    [ "$1" = quick ] || command -v npm >/dev/null || need+=(nodejs npm)
    if [ "$1" = tests ]; then
        command -v valgrind >/dev/null || need+=(valgrind)
        command -v strace >/dev/null || need+=(strace)  # the cueing FMU's system calls in a step
        ls /usr/lib/llvm-*/lib/libclang.so* >/dev/null 2>&1 || need+=(libclang-dev)  # fmi-sim's build
        command -v chromium >/dev/null || need+=(chromium fonts-liberation)           # the viewer's browser test
    fi
    check_disk "$1"
    if [ ${#need[@]} -gt 0 ]; then
        apt_install "${need[@]}"
    fi
    [ "$1" = quick ] && return 0
    # The viewer's build tool (vite) needs Node.js 20.19 or newer; Debian 12's own is 18.
    local node
    node=$(node --version 2>/dev/null | tr -d v)
    if ! printf '20.19.0\n%s\n' "$node" | sort -V -C; then
        die "Node.js ${node:-(none)} is too old for the viewer's build (vite needs 20.19 or newer; Debian 12 ships 18): install Node.js 20 or 22 (NodeSource's Debian packages, or nvm)"
    fi
}

# The Python environment: .venv with tests/requirements.txt and the repository's package
# (python/, editable). pip runs again only when the requirements changed.
python_env() {
    if [ ! -x .venv/bin/python ]; then
        step "creating the Python environment .venv"
        python3 -m venv .venv
    fi
    local stamp=.venv/.requirements.sha256
    if ! sha256sum --status -c "$stamp" 2>/dev/null; then
        step "installing the Python packages of tests/requirements.txt into .venv (FMPy, NumPy, SciPy, Matplotlib, Dask, pandas, pyarrow, libcosimpy, pytest; about 800 MB, a minute or two the first time)"
        # One line a package (pip's "Collecting NAME", without its "(from ...)"), errors in full.
        if ! .venv/bin/python -m pip install --disable-pip-version-check --progress-bar off -r tests/requirements.txt \
                > >(grep --line-buffered -E '^(Collecting|Successfully installed)' | sed -u -E 's/ \(from .*//'); then
            die "pip install -r tests/requirements.txt failed (see above)"
        fi
        sha256sum tests/requirements.txt > "$stamp"
    fi
    # maturin (tests/requirements.txt) builds the compiled master, stewart_fmu._master, beside the
    # package's files; without build isolation: the .venv's maturin, nothing fetched.
    step "installing the repository's Python package (python/: stewart_fmu, stewart-sweep, the compiled master) into .venv, editable (a minute the first time)"
    PATH="$PWD/.venv/bin:$PATH" .venv/bin/python -m pip install --quiet --disable-pip-version-check --no-deps \
        --no-build-isolation -e python
}

# The cross toolchains (Debian 12's packages) for the Windows and aarch64 binaries.
source "$(dirname "${BASH_SOURCE[0]}")/setup_cross.sh"

# The FMUs: the Rust library in release mode for Linux x86-64, Linux aarch64 and Windows x64,
# checked and packaged (the first build takes minutes: the standard library is compiled for
# each foreign target); then the compiled co-simulation master's command
# target/release/stewart-master (its Python extension, stewart_fmu._master, is built by
# `pip install -e python` in python_env: maturin, python/pyproject.toml).
# STEWART_FMU_TARGETS=x86_64-linux (a build-fmu target list) builds those alone, with no
# cross set-up (the platform tests then fail: they need the other binaries).
build_fmus() {
    # The build program in a target folder of its own, run directly (not by `cargo run`): as
    # its dependency the FMU crate resolves otherwise than in its own build and the tests'
    # (target/), and the two would take turns compiling it, a minute or two each time. Its own
    # profile (Cargo.toml's build-tool) compiles its copy of the FMU crate faster.
    step "building the build program (crates/build-fmu, into target/build-fmu; a minute or two the first time)"
    CARGO_TARGET_DIR=target/build-fmu cargo build --profile build-tool -p build-fmu
    if [ -n "${STEWART_FMU_TARGETS:-}" ]; then
        step "building the FMUs for $STEWART_FMU_TARGETS (STEWART_FMU_TARGETS), then packaging into target/fmu/"
        target/build-fmu/build-tool/build-fmu --targets "$STEWART_FMU_TARGETS"
    else
        if [ -n "${BACKGROUND[cross]:-}" ]; then  # started beside the build program (tests/run_all.sh)
            step "waiting for the cross toolchains (target/test-logs/cross.log)"
            finish cross
        fi
        cross_toolchains "${SETUP_KIND:-tests}"
        step "building the FMUs for Linux x86-64, Linux aarch64 and Windows x64, then packaging into target/fmu/ (about 5 minutes the first time on 2 cores, seconds after; a line per platform)"
        target/build-fmu/build-tool/build-fmu
    fi
    step "building the compiled co-simulation master's command (crates/stewart-master; a minute the first time)"
    cargo build --release -p stewart-master
}

# The 3-D viewer: Node packages from the committed lock file, then the static build.
build_viewer() {
    step "building the 3-D viewer: npm ci (three.js, vite, playwright-core; about 70 MB) and vite build into viewer/dist/"
    (cd viewer && npm ci --no-audit --no-fund --loglevel=error && npm run build --silent)
}
