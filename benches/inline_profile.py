"""Where a co-simulation cycle's instructions go, by inlined call chain: the step's physics is
inlined into one function (`integrate_avx2`), so callgrind's per-function table cannot split
it. This builds the FMU's library with its debug information kept (the same code: only the
DWARF differs), runs benches/c/cycle_host.c's count mode under callgrind with per-instruction
counts, maps every instruction of the library to the chain of functions inlined at it
(`addr2line -i`), and prints a tree of inclusive counts per cycle: each line a function and the
source line in it where the next level was inlined.

    .venv/bin/python benches/inline_profile.py              # hover, RK4, FMI 2: writes benches/results/cycle_profile.txt
    .venv/bin/python benches/inline_profile.py drives dopri5 [--depth 14] [--least 10]
        # another motion (cycle_host's CYCLE_SCENARIO), method or depth: printed, nothing written

After `cargo run --release --bin build-fmu` (the host unpacks target/fmu's FMI 2 platform FMU
and replaces its Linux x86-64 binary). The debug build goes to target/profile (a few minutes
the first time). Needs valgrind, gcc and binutils' addr2line. Code the compiler shares between
two branches (or two inlined calls) has one inline chain in the debug information, so its count
stands under one of them only.
"""

import argparse
import collections
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "benches" / "results" / "cycle_profile.txt"
CYCLES = 5000
BASELINE = 1000
PER_CYCLE = CYCLES - BASELINE


def debug_library():
    """The FMU's library for this machine with full debug information, not stripped."""
    env = dict(os.environ, CARGO_PROFILE_RELEASE_DEBUG="full", CARGO_PROFILE_RELEASE_STRIP="none",
               CARGO_TARGET_DIR=str(ROOT / "target" / "profile"))
    # `-p stewart_fmu`: the package and features build-fmu builds (not the workspace's others).
    subprocess.run(["cargo", "build", "--release", "--lib", "-p", "stewart_fmu"], cwd=ROOT, env=env, check=True)
    return ROOT / "target" / "profile" / "release" / "libstewart_fmu.so"


def callgrind(folder, library, scenario, method):
    """Callgrind files of the host's count mode, per instruction: of CYCLES cycles and of
    BASELINE cycles (their difference leaves out the set-up: instantiate, initialise)."""
    with zipfile.ZipFile(ROOT / "target" / "fmu" / "StewartPlatform.fmu") as z:
        z.extractall(folder / "fmu")
    token = re.search(r'guid="([^"]+)"', (folder / "fmu" / "modelDescription.xml").read_text()).group(1)
    binary = folder / "fmu" / "binaries" / "linux64" / "StewartPlatform.so"
    shutil.copy(library, binary)
    host = folder / "cycle_host"
    subprocess.run(["gcc", "-O2", "-g", "-o", str(host), str(ROOT / "benches" / "c" / "cycle_host.c"), "-ldl",
                    "-lpthread"], check=True)
    outs = []
    for cycles in (CYCLES, BASELINE):
        out = folder / f"callgrind.{cycles}"
        subprocess.run(["valgrind", "--tool=callgrind", "--dump-instr=yes", f"--callgrind-out-file={out}", str(host),
                        "fmi2", str(binary), token, method, "count", str(cycles)],
                       check=True, capture_output=True, env=dict(os.environ, CYCLE_SCENARIO=scenario))
        outs.append(out)
    return outs, binary


def self_counts(callgrind_file, object_name):
    """Instructions executed at each address of the object (self cost: calls' inclusive lines
    left out)."""
    names, counts = {}, collections.Counter()
    current_object, address, after_calls = "", 0, False

    def name(kind, text):
        m = re.match(r"\((\d+)\)(?: (.*))?", text)
        if m.group(2) is not None:
            names[(kind, m.group(1))] = m.group(2)
        return names.get((kind, m.group(1)), "")

    for line in open(callgrind_file):
        key, _, value = line.rstrip("\n").partition("=")
        if key in ("ob", "cob"):
            object_name_here = name("ob", value)
            if key == "ob":
                current_object = object_name_here
            continue
        if key in ("fn", "cfn", "fl", "fi", "fe", "cfi", "cfl"):
            continue
        if key == "calls":
            after_calls = True
            continue
        fields = line.split()
        if not fields or fields[0][0] not in "+-*0":
            continue
        a = fields[0]
        if a.startswith("0x"):
            address = int(a, 16)
        elif a[0] in "+-":
            step = int(a[1:], 16) if a[1:].startswith("0x") else int(a[1:])
            address += step if a[0] == "+" else -step
        if after_calls:  # the inclusive cost of a call: not this address's own
            after_calls = False
            continue
        if current_object.endswith(object_name) and len(fields) >= 3:
            counts[address] += int(fields[2])
    return counts


def short(function):
    """A function's last path segment without generic arguments."""
    for _ in range(4):
        function = re.sub(r"<[^<>]*>", "", function)
    return function.split("::")[-1]


def inline_chains(binary, addresses):
    """For each address, its inlined call chain, outermost first: (function, file:line in it)."""
    out = subprocess.run(["addr2line", "-i", "-f", "-C", "-a", "-e", str(binary)] + [hex(a) for a in addresses],
                         capture_output=True, text=True, check=True).stdout.splitlines()
    chains, address, frames, i = {}, None, [], 0
    while i < len(out):
        if out[i].startswith("0x"):
            if address is not None:
                chains[address] = frames[::-1]
            address, frames, i = int(out[i], 16), [], i + 1
            continue
        location = out[i + 1].rsplit("/", 1)[-1].split(" ")[0] if i + 1 < len(out) else "?"
        frames.append((short(out[i]), location))
        i += 2
    if address is not None:
        chains[address] = frames[::-1]
    return chains


def tree(counts, chains, depth):
    """Inclusive counts of every chain prefix, the first element the function compiled on its
    own that holds the address (named with its file: two `do_step`s are two functions)."""
    sums = collections.Counter()
    for address, count in counts.items():
        frames = chains.get(address, [])
        if not frames:
            continue
        function, location = frames[0]
        path = (f"{function} ({location.split(':')[0]})",) + tuple(f"{f}@{loc}" for f, loc in frames[1:])
        for d in range(1, min(depth, len(path)) + 1):
            sums[path[:d]] += count
    return sums


def render(sums, least):
    lines = []

    def walk(prefix):
        children = sorted(((v, p) for p, v in sums.items() if len(p) == len(prefix) + 1 and p[:-1] == prefix),
                          reverse=True)
        for value, path in children:
            if value / PER_CYCLE >= least:
                lines.append(f"{value / PER_CYCLE:9.1f}  {'  ' * len(prefix)}{path[-1]}")
                walk(path)

    walk(())
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scenario", nargs="?", default="hover")
    parser.add_argument("method", nargs="?", default="rk4", choices=("rk4", "dopri5"))
    parser.add_argument("--depth", type=int, default=14, help="levels of inlined calls shown (14)")
    parser.add_argument("--least", type=float, default=10.0, help="instructions per cycle a line needs (10)")
    args = parser.parse_args()
    for tool in ("valgrind", "gcc", "addr2line"):
        if not shutil.which(tool):
            sys.exit(f"inline_profile: {tool} is needed")
    library = debug_library()
    folder = Path(tempfile.mkdtemp(prefix="inline_profile_"))
    try:
        (out, baseline), binary = callgrind(folder, library, args.scenario, args.method)
        counts = self_counts(out, binary.name)
        counts.subtract(self_counts(baseline, binary.name))
        chains = inline_chains(binary, sorted(counts))
        body = render(tree(counts, chains, args.depth), args.least)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    header = [f"inline_profile: {time.strftime('%Y-%m-%d %H:%M')}, FMI 2 {args.method} {args.scenario}, "
              f"callgrind, instructions per cycle of the FMU's library: a run of {CYCLES} cycles less one of {BASELINE}, "
              f"over {PER_CYCLE} (benches/inline_profile.py)",
              "Each function compiled on its own (its file in brackets), with what is inlined into it: a line is "
              "a function and the source line in it where the next level was inlined, its count inclusive of "
              "what is inlined below it, not of the calls it makes (each callee has its own tree).", ""]
    text = "\n".join(header + body) + "\n"
    print(text)
    if (args.scenario, args.method, args.depth, args.least) == ("hover", "rk4", 14, 10.0):
        OUT.write_text(text)
        print(f"written to {OUT.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
