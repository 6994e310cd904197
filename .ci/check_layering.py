#!/usr/bin/env python3
"""Checks that every #include "folder/..." in the tree points down the layer order below.

The layers, bottom to top. A folder may include its own files and those of folders in lower
layers; folders in the same layer never include each other (the coordinator and the worker,
the manifold and the sweep). A unit test (*_test.cc) sits beside the code it tests but belongs to
the top layer: it may include testing/, the test-only code. docs/design/architecture.md shows the same order (checked here too).
"""
import pathlib
import re
import subprocess
import sys

LAYERS = [
    ["base"],
    ["scene"],
    ["mesh"],
    ["shaders"],
    ["gl"],
    ["proto"],
    ["manifold", "sweep"],
    ["refine", "tiles"],
    ["coordinator", "worker", "tools", "colmap"],
    ["report"],
    ["app"],
    ["testing"],
    ["bench", "tests"],
]

INCLUDE = re.compile(r'^\s*#\s*include\s+"([a-z_0-9]+)/')


def layer_line():
    """The order as docs/design/architecture.md writes it."""
    parts = [g[0] if len(g) == 1 else "{" + ", ".join(g) + "}" for g in LAYERS]
    return " → ".join(parts)


def main():
    root = pathlib.Path(__file__).resolve().parent.parent
    level = {folder: i for i, group in enumerate(LAYERS) for folder in group}
    files = subprocess.run(["git", "ls-files", "*.cc", "*.h"], cwd=root, check=True,
                           capture_output=True, text=True).stdout.split()
    problems = []
    for name in files:
        folder = name.split("/")[0]
        if folder not in level:
            problems.append(f"{name}: folder '{folder}' is in no layer (.ci/check_layering.py)")
            continue
        own_level = level["tests"] + 1 if name.endswith("_test.cc") else level[folder]
        for number, line in enumerate((root / name).read_text().splitlines(), 1):
            match = INCLUDE.match(line)
            if not match or match.group(1) == folder:
                continue
            target = match.group(1)
            if target not in level:
                continue  # a third-party header with a folder of its own
            if level[target] >= own_level:
                how = "the same layer" if level[target] == level[folder] else "a higher layer"
                problems.append(f"{name}:{number}: includes {target}/, {how} than {folder}/")
    docs = (root / "docs" / "design" / "architecture.md").read_text()
    if layer_line() not in docs:
        problems.append(
            f"docs/design/architecture.md does not show the layer order: {layer_line()}")
    for problem in problems:
        print(problem)
    print(f"layering: {len(files)} files, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
