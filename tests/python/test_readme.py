"""The README's Python example runs as written (like diffsol's README code check)."""

import os
import re

from stewart_fmu import ROOT


def test_readme_python_blocks_run(platform_fmu):
    text = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert blocks, "the README has a Python example"
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        for block in blocks:
            namespace = {}
            exec(compile(block, "README.md", "exec"), namespace)
            if "result" in namespace:
                assert len(namespace["result"]) > 10
    finally:
        os.chdir(cwd)
