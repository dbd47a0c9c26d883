"""Runs the README's tour where it is called from (a test gives a temporary folder): each
```python block in its own namespace, in order; prints one JSON line with what the tests check
(the values each block leaves under the names in KEPT). Run by the interpreter under test:
the repository's .venv (tests/python/test_readme.py) or a fresh environment with the wheel
(tests/python/test_wheel.py).

    python readme_tour.py README.md
"""

import json
import re
import sys

import numpy as np

KEPT = ("result", "tilted", "t", "rows", "errors", "status", "pitch", "commanded", "address")


def plain(value):
    if isinstance(value, np.ndarray) and value.dtype.names:
        return {n: value[n].tolist() for n in value.dtype.names}
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    return value


def blocks(text, language):
    return re.findall(rf"```{language}\n(.*?)```", text, re.S)


def main():
    text = open(sys.argv[1]).read()
    kept = []
    for i, block in enumerate(blocks(text, "python")):
        namespace = {"__name__": "__main__"}
        exec(compile(block, f"README.md, python block {i + 1}", "exec"), namespace)
        kept.append({name: plain(namespace[name]) for name in KEPT if name in namespace})
    print(json.dumps(kept))


if __name__ == "__main__":
    main()
