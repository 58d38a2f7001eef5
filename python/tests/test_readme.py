"""The Python examples of README.md and python/README.md run as written."""

import os
import re

import pytest

from conftest import REPO

BLOCK = re.compile(r"```python\n(.*?)```", re.S)


def examples():
    for name in ("README.md", "python/README.md"):
        text = (REPO / name).read_text()
        for k, code in enumerate(BLOCK.findall(text)):
            yield pytest.param(code, id=f"{name}#{k}")


@pytest.mark.parametrize("code", list(examples()))
def test_readme_example_runs(code):
    cwd = os.getcwd()
    os.chdir(REPO)  # examples name scenes relative to the repository
    try:
        env = {}
        exec(compile(code, "<readme>", "exec"), env)
    finally:
        os.chdir(cwd)
    assert env["x"].shape[1] == 3


def test_both_readmes_have_an_example():
    ids = [p.id for p in examples()]
    assert any(i.startswith("README.md") for i in ids)
    assert any(i.startswith("python/README.md") for i in ids)
