"""Builds the wheels of the Python package stewart_fmu with maturin (python/pyproject.toml), one
for each platform the package runs on, into target/wheels/:

    stewart_fmu-<version>-cp311-abi3-manylinux_2_34_x86_64.whl
    stewart_fmu-<version>-cp311-abi3-manylinux_2_34_aarch64.whl
    stewart_fmu-<version>-cp311-abi3-win_amd64.whl

Each carries the package's Python files, the compiled master built for its platform (the
extension stewart_fmu._master, Python 3.11+'s stable ABI), the viewer page and the FMUs with all
their binaries in stewart_fmu/data/. manylinux_2_34: the FMUs' glibc rule (build-fmu refuses a
binary that asks for more), which maturin checks for the extension too. FMI 2 has one binary
folder for 64-bit Linux, `linux64`, which FMPy and FMI Library read on x86-64 and aarch64
alike: the aarch64 wheel's FMI 2 FMUs (and the SSP files' copies) carry there the aarch64 binary
of the same build, taken from the FMI 3 FMU (`binaries/aarch64-linux`); every other file is the
repository's, byte for byte.

The foreign extensions are built as build-fmu builds the FMUs' foreign binaries
(crates/build-fmu/src/platforms.rs): with rustup's target where it is installed, otherwise with
Debian 12's Rust compiler and the standard library compiled from its source (`-Zbuild-std`, in
build-fmu's target/cross/<triple>, so the standard library is compiled once for both), linked by the
target's C compiler from Debian's cross packages. The Windows extension imports python3.dll, the
stable ABI's DLL, which PyO3 links by name (raw-dylib): no Windows Python is needed to build it.

Needs the FMUs of every platform and the viewer page built first: `bash python/build_wheels.sh`
does all of it (the README's command). Each build runs in a copy of the package under
target/wheel-stage/, so nothing is written into python/.

    .venv/bin/python python/build_wheels.py [--platforms x86_64-linux,aarch64-linux,x86_64-windows]
"""

import argparse
import io
import os
import re
import shutil
import subprocess
import sys
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FMU_DIR = ROOT / "target" / "fmu"
VIEWER = ROOT / "viewer" / "dist"
WHEELS = ROOT / "target" / "wheels"
STAGE = ROOT / "target" / "wheel-stage"
PACKAGED = ["StewartPlatform.fmu", "StewartController.fmu", "StewartCueing.fmu", "StewartSystem.ssp",
            "StewartSystemDrives.ssp", "StewartSystemHydraulic.ssp", "StewartSystemPowerUnit.ssp", "StewartMotionSystem.ssp",
            "fmi3/StewartPlatform.fmu", "fmi3/StewartController.fmu", "fmi3/StewartCueing.fmu"]

# platform (build-fmu's names): Rust's target triple, maturin's --compatibility, the wheel's
# platform tag, the linker of a foreign build, the FMI 3 folder whose binary the FMI 2 FMUs carry
# in linux64 (None: the FMUs as build-fmu packs them).
PLATFORMS = {
    "x86_64-linux": ("x86_64-unknown-linux-gnu", "manylinux_2_34", "manylinux_2_34_x86_64", None, None),
    "aarch64-linux": ("aarch64-unknown-linux-gnu", "manylinux_2_34", "manylinux_2_34_aarch64", "aarch64-linux-gnu-gcc",
                      "aarch64-linux"),
    "x86_64-windows": ("x86_64-pc-windows-gnu", None, "win_amd64", "x86_64-w64-mingw32-gcc", None),
}


def wheel_name(platform, version):
    return f"stewart_fmu-{version}-cp311-abi3-{PLATFORMS[platform][2]}.whl"


def version():
    """The workspace's one version (Cargo.toml's [workspace.package])."""
    text = (ROOT / "Cargo.toml").read_text()
    return re.search(r'\[workspace\.package\]\s*\nversion = "([^"]+)"', text).group(1)


def host_triple():
    out = subprocess.run(["rustc", "-vV"], capture_output=True, text=True, check=True).stdout
    return re.search(r"^host: (\S+)", out, re.M).group(1)


def has_target_std(triple):
    """Whether the invoking toolchain has `triple`'s standard library (rustup's target)."""
    run = subprocess.run(["rustc", "--print", "target-libdir", "--target", triple], capture_output=True, text=True)
    libdir = Path(run.stdout.strip())
    return run.returncode == 0 and libdir.is_dir() and any(p.name.startswith("libstd-") for p in libdir.iterdir())


def cross_build(triple, linker):
    """(environment, cargo arguments, target folder, what builds it) for a foreign target, as
    build-fmu builds the FMUs' binaries."""
    env = dict(os.environ)
    variable = f"CARGO_TARGET_{triple.upper().replace('-', '_')}_LINKER"
    env.setdefault(variable, linker)
    if shutil.which(env[variable]) is None:
        sys.exit(f"build_wheels: the linker {env[variable]} for {triple} is missing: bash tests/setup_cross.sh "
                 f"installs it (Debian 12), or set {variable}")
    cross = ROOT / "target" / "cross" / triple  # build-fmu's folder for this target
    if has_target_std(triple):
        return env, [], cross, f"the installed {triple} standard library"
    cargo = os.environ.get("STEWART_BUILD_STD_CARGO", "/usr/bin/cargo")
    rustc = os.environ.get("STEWART_BUILD_STD_RUSTC", "/usr/bin/rustc")
    sysroot = subprocess.run([rustc, "--print", "sysroot"], capture_output=True, text=True).stdout.strip() \
        if Path(rustc).exists() else ""
    if not (Path(cargo).exists() and sysroot and (Path(sysroot) / "lib/rustlib/src/rust/library/std").is_dir()):
        sys.exit(f"build_wheels: no Rust standard library for {triple}: bash tests/setup_cross.sh (Debian 12), or "
                 f"rustup target add {triple}")
    # maturin runs the `cargo` on PATH: this one, whose rustc compiles the standard library too.
    env.update(PATH=f"{Path(cargo).parent}{os.pathsep}{env['PATH']}", RUSTC=rustc, RUSTC_BOOTSTRAP="1")
    env.pop("RUSTUP_TOOLCHAIN", None)
    how = subprocess.run([rustc, "--version"], capture_output=True, text=True).stdout.split()[:2]
    return env, ["-Zbuild-std=std,panic_unwind"], cross, f"{' '.join(how)} with the standard library compiled from its source"


def fmi2_with_binary(data, binaries):
    """An FMI 2 FMU (zip bytes) with binaries/linux64/<id>.so replaced by `binaries[<id>]`."""
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(data)) as src, zipfile.ZipFile(out, "w") as dst:
        replaced = 0
        for info in src.infolist():
            body = src.read(info)
            match = re.fullmatch(r"binaries/linux64/(\w+)\.so", info.filename)
            if match:
                body = binaries[match.group(1)]
                replaced += 1
            dst.writestr(info, body, compress_type=info.compress_type)
    assert replaced == 1, "an FMI 2 FMU carries one binaries/linux64 binary"
    return out.getvalue()


def ssp_with_binary(data, binaries):
    """An SSP (zip bytes) whose FMI 2 FMUs carry `binaries` in linux64."""
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(data)) as src, zipfile.ZipFile(out, "w") as dst:
        for info in src.infolist():
            body = src.read(info)
            if info.filename.endswith(".fmu"):
                body = fmi2_with_binary(body, binaries)
            dst.writestr(info, body, compress_type=info.compress_type)
    return out.getvalue()


def linux_binaries(fmi3_folder):
    """{model identifier: the binary of that FMI 3 folder} from the FMI 3 FMUs."""
    binaries = {}
    for fmu in sorted((FMU_DIR / "fmi3").glob("*.fmu")):
        with zipfile.ZipFile(fmu) as z:
            for name in z.namelist():
                match = re.fullmatch(rf"binaries/{fmi3_folder}/(\w+)\.so", name)
                if match:
                    binaries[match.group(1)] = z.read(name)
    return binaries


def incomplete_fmus():
    """(FMU, binary folder) pairs missing from target/fmu: each wheel carries the FMUs with the
    binaries of every platform (FMI 2: linux64 and win64, the SSP files' copies too; FMI 3: all
    three)."""
    missing = []
    for name in (n for n in PACKAGED if n.endswith(".fmu")):
        folders = ["x86_64-linux", "aarch64-linux", "x86_64-windows"] if name.startswith("fmi3/") else ["linux64", "win64"]
        with zipfile.ZipFile(FMU_DIR / name) as z:
            names = z.namelist()
        missing += [(name, f) for f in folders if not any(n.startswith(f"binaries/{f}/") for n in names)]
    return missing


def stage(platform):
    """target/wheel-stage/<platform>/: pyproject.toml (its manifest path made absolute), the
    licence, a copy of the package and its data (the FMUs, the viewer page). Returns the folder."""
    folder = STAGE / platform
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    pyproject = (ROOT / "python" / "pyproject.toml").read_text()
    manifest = ROOT / "crates" / "stewart-master-py" / "Cargo.toml"
    pyproject, n = re.subn(r'(?m)^manifest-path = ".*"$', f'manifest-path = "{manifest.as_posix()}"', pyproject)
    assert n == 1, "python/pyproject.toml names the extension's manifest once"
    (folder / "pyproject.toml").write_text(pyproject)
    # The licence beside pyproject.toml: maturin puts it into the wheel's .dist-info/licenses/.
    shutil.copyfile(ROOT / "LICENSE", folder / "LICENSE")
    # Not the extension an editable install (`pip install -e python`) built for this machine.
    shutil.copytree(ROOT / "python" / "stewart_fmu", folder / "stewart_fmu",
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc", "_master.*"))
    data = folder / "stewart_fmu" / "data"
    fmi3_folder = PLATFORMS[platform][4]
    binaries = linux_binaries(fmi3_folder) if fmi3_folder else None
    for name in PACKAGED:
        target = data / "fmu" / name
        target.parent.mkdir(parents=True, exist_ok=True)
        body = (FMU_DIR / name).read_bytes()
        if binaries and not name.startswith("fmi3/"):
            body = ssp_with_binary(body, binaries) if name.endswith(".ssp") else fmi2_with_binary(body, binaries)
        target.write_bytes(body)
    shutil.copytree(VIEWER, data / "viewer")
    return folder


def build(platform, maturin):
    """Builds one wheel into target/wheels/; returns its path."""
    triple, compatibility, _, linker, _ = PLATFORMS[platform]
    folder = stage(platform)
    if triple == host_triple():
        # target/release, where `pip install -e python` builds the extension too.
        env, extra, target_dir, how = dict(os.environ), [], ROOT / "target", "this machine's toolchain"
    else:
        env, extra, target_dir, how = cross_build(triple, linker)
    print(f"build_wheels: {platform}: the extension with {how}, then the wheel", flush=True)
    command = [str(maturin), "build", "--release", "--target-dir", str(target_dir), "--out", str(WHEELS), "--quiet",
               *([] if triple == host_triple() else ["--target", triple]), *extra]
    if compatibility:
        command += ["--compatibility", compatibility, "--auditwheel", "check"]
    started = time.monotonic()
    run = subprocess.run(command, cwd=folder, env=env)
    if run.returncode != 0:
        sys.exit(f"build_wheels: maturin failed for {platform} (exit {run.returncode})")
    wheel = WHEELS / wheel_name(platform, version())
    if not wheel.is_file():
        sys.exit(f"build_wheels: maturin did not write {wheel.name}: {sorted(p.name for p in WHEELS.glob('*.whl'))}")
    print(f"build_wheels: {wheel.relative_to(ROOT)}: {wheel.stat().st_size / 1e6:.1f} MB, "
          f"{time.monotonic() - started:.0f} s", flush=True)
    return wheel


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--platforms", default=",".join(PLATFORMS),
                        help=f"a comma-separated list of {', '.join(PLATFORMS)} (default: all)")
    args = parser.parse_args(argv)
    platforms = [p.strip() for p in args.platforms.split(",") if p.strip()]
    for p in platforms:
        if p not in PLATFORMS:
            parser.error(f"unknown platform {p}: {', '.join(PLATFORMS)}")
    missing = [str(FMU_DIR / n) for n in PACKAGED if not (FMU_DIR / n).is_file()]
    missing += [] if (VIEWER / "index.html").is_file() else [str(VIEWER / "index.html")]
    if missing:
        sys.exit(f"build_wheels: {', '.join(missing)} missing: build the FMUs (cargo run --release --bin build-fmu) and "
                 "the viewer (npm ci && npm run build in viewer/) first; bash python/build_wheels.sh does both")
    incomplete = [f"{name} (binaries/{folder} missing)" for name, folder in incomplete_fmus()]
    if incomplete:
        sys.exit(f"build_wheels: the FMUs do not carry every platform's binary: {'; '.join(incomplete)}: build them for "
                 "every platform (cargo run --release --bin build-fmu, without --targets)")
    maturin = Path(sys.executable).parent / "maturin"
    if not maturin.exists():
        sys.exit(f"build_wheels: {maturin} is missing: pip install -r tests/requirements.txt (maturin) into this "
                 "environment; bash python/build_wheels.sh does")
    WHEELS.mkdir(parents=True, exist_ok=True)
    # Only this build's wheels of the package stay: not older versions', nor the editable one
    # that `pip install -e python` leaves here.
    for old in WHEELS.glob("stewart_fmu-*.whl"):
        if old.name not in {wheel_name(p, version()) for p in PLATFORMS if p not in platforms}:
            old.unlink()
    started = time.monotonic()
    for p in platforms:
        build(p, maturin)
    print(f"build_wheels: {len(platforms)} wheel(s) in {time.monotonic() - started:.0f} s", flush=True)


if __name__ == "__main__":
    main()
