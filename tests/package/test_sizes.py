"""Size limits of the source: no function over 120 lines, no module over 600 lines.

Long functions and modules are where a new block costs the most edits; docs/architecture.md's
recipes assume each block's code is short enough to read whole. Lines are counted as the file
has them (docstrings and comments included); a function's length runs from its ``def`` (or
first decorator) to its last line.
"""

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src" / "imdrive"
MAX_FUNCTION_LINES = 120
MAX_MODULE_LINES = 600


def _modules():
    return sorted(p for p in SRC.rglob("*.py") if "__pycache__" not in p.parts)


def function_lengths(path: Path) -> list[tuple[str, int]]:
    """``(qualified name, lines)`` of every function and method of a module."""
    tree = ast.parse(path.read_text(), filename=str(path))
    out = []

    def walk(node, prefix):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                name = f"{prefix}{child.name}"
                if not isinstance(child, ast.ClassDef):
                    first = min([child.lineno, *(d.lineno for d in child.decorator_list)])
                    out.append((name, child.end_lineno - first + 1))
                walk(child, name + ".")
            else:
                walk(child, prefix)

    walk(tree, "")
    return out


def test_the_walker_measures_what_it_should(tmp_path):
    f = tmp_path / "m.py"
    f.write_text(
        "@dec\ndef a():\n    def inner():\n        pass\n    return 1\n\n\n"
        "class C:\n    def m(self):\n        x = 1\n        return x\n"
    )
    assert dict(function_lengths(f)) == {"a": 5, "a.inner": 2, "C.m": 3}


def test_no_function_over_120_lines():
    long = [
        f"{p.relative_to(SRC)}:{name} ({n} lines)"
        for p in _modules()
        for name, n in function_lengths(p)
        if n > MAX_FUNCTION_LINES
    ]
    assert not long, f"functions over {MAX_FUNCTION_LINES} lines (split them): {long}"


def test_no_module_over_600_lines():
    long = [
        f"{p.relative_to(SRC)} ({n} lines)"
        for p in _modules()
        if (n := len(p.read_text().splitlines())) > MAX_MODULE_LINES
    ]
    assert not long, f"modules over {MAX_MODULE_LINES} lines (split them): {long}"
