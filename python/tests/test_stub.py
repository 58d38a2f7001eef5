"""weft.pyi names exactly what the module has: classes, methods, properties, module constants."""

import ast
import inspect

import weft
from conftest import REPO


def stub_names():
    tree = ast.parse((REPO / "python" / "weft.pyi").read_text())
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            top.add(node.name)
            members[node.name] = {n.name for n in node.body if isinstance(n, ast.FunctionDef)} - {"__init__"}
        elif isinstance(node, ast.AnnAssign):
            top.add(node.target.id)
    return top, members


def public(obj):
    return {n for n in dir(obj) if not n.startswith("_")} | ({"__len__"} & set(vars(obj)) if inspect.isclass(obj) else set())


def test_stub_matches_the_module():
    top, members = stub_names()
    assert "__version__" in top and weft.__version__
    # The package also holds the compiled module itself, `weft.weft`.
    module = public(weft) - {"weft"}
    assert top - {"__version__"} == module, top ^ module
    for cls, names in members.items():
        have = public(getattr(weft, cls))
        if issubclass(getattr(weft, cls), BaseException):
            have = set()  # exception attributes come from BaseException
        assert names == have, (cls, names ^ have)
