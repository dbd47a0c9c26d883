"""The packaged FMUs on every platform they carry: the C host `tests/c/platform_host.c` built
for each (gcc, mingw-w64, the aarch64 gcc) and run there (natively, under wine, under
qemu-user) on the binaries unpacked from the same FMU files, with the same scripts. What the
host prints is deterministic (hex bits, statuses, messages), so the platforms' runs compare
line by line (test_platforms.py).

The toolchains come from Debian 12's packages (tests/setup_cross.sh installs them).
"""

import contextlib
import fcntl
import os
import re
import shutil
import struct
import subprocess
import urllib.parse
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HOST_SOURCE = ROOT / "tests" / "c" / "platform_host.c"
WINE_SHIM_SOURCE = ROOT / "tests" / "c" / "wine_bcryptprimitives.c"
BUILD = ROOT / "target" / "platform-hosts"
# Debian 12's places (tests/setup_cross.sh); elsewhere wine64 or wine and qemu-aarch64 on
# PATH, and the aarch64 C library's root named by STEWART_AARCH64_SYSROOT.
WINE = "/usr/lib/wine/wine64" if Path("/usr/lib/wine/wine64").exists() else (
    shutil.which("wine64") or shutil.which("wine") or "/usr/lib/wine/wine64")
WINESERVER = "/usr/lib/wine/wineserver64" if Path("/usr/lib/wine/wineserver64").exists() else (
    shutil.which("wineserver") or "/usr/lib/wine/wineserver64")
QEMU = shutil.which("qemu-aarch64-static") or shutil.which("qemu-aarch64") or "qemu-aarch64-static"
AARCH64_SYSROOT = os.environ.get("STEWART_AARCH64_SYSROOT", "/usr/aarch64-linux-gnu")

# platform: the FMI 2 folder (None: FMI 3 only), the extension, the C compiler and its
# flags, the command that runs a program built for it here.
PLATFORMS = {
    "x86_64-linux": {"fmi2": "linux64", "extension": ".so", "cc": ["gcc"], "libs": ["-ldl"], "runner": []},
    "x86_64-windows": {"fmi2": "win64", "extension": ".dll",
                       "cc": ["x86_64-w64-mingw32-gcc", "-municode", "-static"], "libs": [], "runner": [WINE]},
    "aarch64-linux": {"fmi2": None, "extension": ".so", "cc": ["aarch64-linux-gnu-gcc"], "libs": ["-ldl"],
                      "runner": [QEMU, "-L", AARCH64_SYSROOT]},
}
REFERENCE = "x86_64-linux"


def host_path(platform):
    return BUILD / platform / ("platform_host.exe" if platform == "x86_64-windows" else "platform_host")


def build_hosts():
    """Compiles the host for every platform (warnings are errors) and, for wine 8, the
    bcryptprimitives.dll shim beside the Windows host. Returns the paths."""
    built = {}
    for platform, p in PLATFORMS.items():
        out = host_path(platform)
        out.parent.mkdir(parents=True, exist_ok=True)
        subprocess.run(p["cc"] + ["-std=c11", "-O1", "-Wall", "-Wextra", "-Werror", "-o", str(out), str(HOST_SOURCE)]
                       + p["libs"], check=True)
        built[platform] = out
    shim = BUILD / "x86_64-windows" / "bcryptprimitives.dll"
    subprocess.run(["x86_64-w64-mingw32-gcc", "-O1", "-Wall", "-Werror", "-shared", "-o", str(shim),
                    str(WINE_SHIM_SOURCE), "-lbcrypt"], check=True)
    return built


def wine_environment():
    """A wine prefix of the repository's own (target/wine-prefix, made on first use), quiet,
    without the Mono and Gecko installers, the shim beside the .exe preferred to any built-in."""
    env = dict(os.environ)
    env.update(WINEPREFIX=str(ROOT / "target" / "wine-prefix"), WINEDEBUG="-all",
               WINEDLLOVERRIDES="mscoree,mshtml=;bcryptprimitives=n,b")
    env.pop("DISPLAY", None)
    return env


def windows_path(path):
    """wine's name for a path of this machine: drive Z: is the root."""
    return "Z:" + str(path).replace("/", "\\")


def resource_location(path, platform, version):
    """The FMU's resources folder as a host on `platform` passes it: FMI 2 a file URI
    (percent-encoded; `file:///Z:/...` on Windows), FMI 3 a native path with a trailing
    separator."""
    native = windows_path(path) if platform == "x86_64-windows" else str(path)
    if version == 3:
        return native + ("\\" if platform == "x86_64-windows" else "/")
    text = native.replace("\\", "/")
    return "file://" + ("/" if not text.startswith("/") else "") + urllib.parse.quote(text, safe="/:")


def unpack(fmu, folder):
    folder.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return folder


def binary(unpacked, version, platform, model_identifier):
    folder = PLATFORMS[platform]["fmi2"] if version == 2 else platform
    return unpacked / "binaries" / folder / (model_identifier + PLATFORMS[platform]["extension"])


def declarations(model_description, model):
    """The script lines that declare a model to the host: its token, its state counts and every
    variable (FMI 2: an array's elements' references in order; FMI 3: one reference, the size)."""
    root = ET.parse(model_description).getroot()
    version = 2 if root.get("fmiVersion") == "2.0" else 3
    lines = [f"token {model} {root.get('guid') if version == 2 else root.get('instantiationToken')}"]
    structure = root.find("ModelStructure")
    if version == 2:
        derivatives = structure.find("Derivatives")
        states = 0 if derivatives is None else len(derivatives)
        lines.append(f"states {model} {states} {root.get('numberOfEventIndicators', '0')}")
        groups = {}
        for sv in root.find("ModelVariables"):
            kind = next(iter(sv)).tag
            code = {"Real": "R", "Integer": "I", "Boolean": "B", "Enumeration": "I"}.get(kind)
            if code is None:
                continue
            base = re.sub(r"\[[^\]]*\]", "", sv.get("name"))  # r[1] -> r, der(v[1]) -> der(v)
            groups.setdefault((base, code), []).append(int(sv.get("valueReference")))
        for (base, code), vrs in groups.items():
            if len(vrs) <= 32:
                lines.append(f"var {model} {base} {code} {len(vrs)} " + " ".join(map(str, vrs)))
    else:
        for v in root.find("ModelVariables"):
            code = {"Float64": "R", "Int32": "I", "Boolean": "B", "Enumeration": "I"}.get(v.tag)
            if code is None:
                continue
            size = 1
            for d in v.findall("Dimension"):
                size *= int(d.get("start"))
            if size <= 32:
                lines.append(f"var {model} {v.get('name')} {code} {size} {v.get('valueReference')}")
    return lines


def ensure_wine_prefix():
    """Makes the wine prefix once (wineboot; about 10-30 s), so that no test run pays for it."""
    env = wine_environment()
    if not Path(env["WINEPREFIX"], "system.reg").exists():
        subprocess.run([WINE, "wineboot", "--init"], env=env, capture_output=True, timeout=600)
        subprocess.run([WINESERVER, "-w"], env=env, capture_output=True, timeout=600)


def run_host(platform, version, platform_binary, controller_binary, uri, script, timeout=600):
    """Runs the host built for `platform` on the script; returns (exit code, stdout, stderr)."""
    exe = host_path(platform)
    paths = [platform_binary, controller_binary]
    env = None
    if platform == "x86_64-windows":
        exe, paths, env = windows_path(exe), [windows_path(p) for p in paths], wine_environment()
    command = PLATFORMS[platform]["runner"] + [str(exe), str(version)] + [str(p) for p in paths] + [uri]
    done = subprocess.run(command, input=script, capture_output=True, text=True, encoding="utf-8", env=env,
                          timeout=timeout)
    if platform == "x86_64-windows" and done.returncode != 0 and not done.stdout and not done.stderr:
        # Nothing printed, not even the host's first line or a load error: wine itself did not
        # start the host (seen once, in the test command on d15d8cf; the same run passed alone).
        # Wait for the wineserver and run once more; the host's own failures always print.
        print(f"platforms: wine exited {done.returncode} before the host printed anything; again after wineserver -w")
        subprocess.run([WINESERVER, "-w"], env=env, timeout=120, check=False)
        done = subprocess.run(command, input=script, capture_output=True, text=True, encoding="utf-8", env=env,
                              timeout=timeout)
    return done.returncode, done.stdout, done.stderr


def values_of(line):
    """The float values of a line of hex bits (none for other lines)."""
    words = line.split()
    out = []
    for w in words:
        if len(w) == 16 and all(c in "0123456789abcdef" for c in w):
            out.append(struct.unpack("<d", struct.pack("<Q", int(w, 16)))[0])
    return out


def compare(reference, other):
    """(lines that differ, the largest difference of a value, the first differing pair) between
    two hosts' outputs."""
    a, b = reference.splitlines(), other.splitlines()
    differing, largest, first = abs(len(a) - len(b)), 0.0, None
    for x, y in zip(a, b):
        if x == y:
            continue
        differing += 1
        first = first or (x, y)
        vx, vy = values_of(x), values_of(y)
        for p, q in zip(vx, vy):
            if p != q:
                largest = max(largest, abs(p - q) if (p == p and q == q) else float("inf"))
    return differing, largest, first


def tools_missing():
    """The cross tools this machine lacks (tests/setup_cross.sh installs them)."""
    needed = ["gcc", "x86_64-w64-mingw32-gcc", "x86_64-w64-mingw32-objdump", "aarch64-linux-gnu-gcc",
              "aarch64-linux-gnu-nm", QEMU]
    missing = [t for t in needed if shutil.which(t) is None]
    if not Path(WINE).exists():
        missing.append("wine64")
    if not Path(AARCH64_SYSROOT, "lib", "libc.so.6").exists():
        missing.append(AARCH64_SYSROOT + "/lib/libc.so.6")
    return missing


# An arm64 CPython with FMPy, run under qemu-user: Debian 12's own arm64 packages unpacked
# (not installed) into target/arm64-python/root with a private apt state, and FMPy, NumPy,
# lxml and attrs from PyPI's aarch64 wheels into target/arm64-python/site.
ARM64_PYTHON = ROOT / "target" / "arm64-python"
ARM64_DEBS = ["python3.11-minimal", "libpython3.11-minimal", "libpython3.11-stdlib", "libc6", "libgcc-s1", "libstdc++6",
              "libbz2-1.0", "libcrypt1", "libdb5.3", "libexpat1", "libffi8", "liblzma5", "libncursesw6", "libnsl2",
              "libreadline8", "libsqlite3-0", "libtinfo6", "libtirpc3", "libuuid1", "zlib1g", "libssl3",
              "libgssapi-krb5-2", "libkrb5-3", "libk5crypto3", "libkrb5support0", "libcom-err2", "libkeyutils1"]
ARM64_WHEELS = ["fmpy==0.3.32", "numpy==2.4.6", "lxml==6.1.3", "attrs==26.1.0"]


@contextlib.contextmanager
def made_once(name):
    """Holds target/NAME.lock while something shared is made or checked: the test workers
    (pytest-xdist) start together, and one must not remove or rewrite a folder another is
    running from."""
    lock = ROOT / "target" / f"{name}.lock"
    lock.parent.mkdir(parents=True, exist_ok=True)
    with open(lock, "a") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def arm64_python(pip_python):
    """The command that runs the arm64 Python under qemu, and its site folder (made once:
    about 12 MB of Debian packages and 40 MB of wheels, seconds)."""
    with made_once("arm64-python"):
        return _arm64_python(pip_python)


def _arm64_python(pip_python):
    root, site, stamp = ARM64_PYTHON / "root", ARM64_PYTHON / "site", ARM64_PYTHON / "ready"
    wanted = " ".join(ARM64_DEBS + ARM64_WHEELS)
    if not stamp.exists() or stamp.read_text() != wanted:
        shutil.rmtree(ARM64_PYTHON, ignore_errors=True)
        apt, debs = ARM64_PYTHON / "apt", ARM64_PYTHON / "debs"
        for d in (apt / "state" / "lists" / "partial", apt / "cache" / "archives" / "partial", debs, root):
            d.mkdir(parents=True, exist_ok=True)
        (apt / "status").write_text("")
        options = ["-o", f"Dir::State={apt / 'state'}", "-o", f"Dir::Cache={apt / 'cache'}",
                   "-o", f"Dir::State::status={apt / 'status'}", "-o", "APT::Architecture=arm64",
                   "-o", "APT::Architectures=arm64", "-o", "APT::Sandbox::User=root"]
        subprocess.run(["apt-get", *options, "update", "-qq"], check=True, capture_output=True)
        subprocess.run(["apt-get", *options, "download", "-qq", *ARM64_DEBS], check=True, capture_output=True,
                       cwd=debs)
        for deb in sorted(debs.glob("*.deb")):
            subprocess.run(["dpkg-deb", "-x", str(deb), str(root)], check=True)
        platforms = [a for p in ("manylinux_2_28_aarch64", "manylinux_2_17_aarch64", "manylinux2014_aarch64")
                     for a in ("--platform", p)]
        subprocess.run([str(pip_python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--no-deps",
                        "--target", str(site), *platforms, "--python-version", "3.11", "--implementation", "cp",
                        "--abi", "cp311", "--only-binary=:all:", *ARM64_WHEELS], check=True)
        stamp.write_text(wanted)
    return [QEMU, "-L", str(root), str(root / "usr" / "bin" / "python3.11")], site
