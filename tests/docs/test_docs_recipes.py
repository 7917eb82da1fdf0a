"""The recipes of docs/architecture.md name only things that exist.

Every backticked identifier in the *Recipes* section that names a function, a constant, a
record field or a setting (``foo_bar``, ``FOO_BAR``; dotted names by each part) must be defined
somewhere in ``src/imdrive``: as a function, class, assignment, argument, keyword or record
field name, or a module. A renamed or removed function then fails here instead of leaving
the recipe to drift.
"""

import ast
import functools
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOC = ROOT / "docs" / "architecture.md"
SRC = ROOT / "src" / "imdrive"

#: a backticked identifier with an underscore (``foo_bar``, ``FOO_BAR``, ``_stage``) or a
#: constant in capitals (``SECTIONS``)
IDENT = re.compile(r"^_?[A-Za-z][A-Za-z0-9]*(_[A-Za-z0-9]+)+$|^_[a-z0-9]+$|^[A-Z][A-Z0-9]{2,}$")


def recipe_section(text: str) -> str:
    start = text.index("## Recipes")
    end = text.find("\n## ", start + 1)
    return text[start : end if end > 0 else len(text)]


def recipe_identifiers(text: str) -> set[str]:
    """Identifiers in backticks (code spans) of the recipes; call parentheses, attribute
    paths and keyword values are split off; placeholders (``<name>``) are skipped."""
    out = set()
    for span in re.findall(r"`([^`]+)`", recipe_section(text)):
        if "<" in span or "/" in span:
            continue  # a placeholder or a path
        for token in re.findall(r"[A-Za-z_][A-Za-z0-9_.]*", span):
            for part in token.split("."):
                if IDENT.match(part):
                    out.add(part)
    return out


@functools.cache
def defined_names() -> frozenset[str]:
    """Every name ``src/imdrive`` defines: modules, functions, classes, assignment targets,
    arguments, keywords and identifier-like string constants (record fields). Parsed once
    per run (every module of ``src``: 2-4 s on 2 cores), for the two tests that read it."""
    names = set()
    for path in SRC.rglob("*.py"):
        names.update(path.relative_to(SRC).with_suffix("").parts)
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
                names.add(node.name)
            elif isinstance(node, ast.Name | ast.arg):
                names.add(node.id if isinstance(node, ast.Name) else node.arg)
            elif isinstance(node, ast.Attribute):
                names.add(node.attr)
            elif isinstance(node, ast.keyword) and node.arg:
                names.add(node.arg)
            elif isinstance(node, ast.Constant) and isinstance(node.value, str):
                if node.value.isidentifier():
                    names.add(node.value)
    return frozenset(names)


def test_identifier_pattern():
    text = "## Recipes\nuse `foo_bar(x)`, `FOO_BAR`, `a.b_c`, `<name>_step`, `x`, `src/a_b.py`\n"
    assert recipe_identifiers(text) == {"foo_bar", "FOO_BAR", "b_c"}
    assert recipe_identifiers("## Recipes\n`SECTIONS` and `Scenario`\n") == {"SECTIONS"}


def test_recipe_identifiers_exist_in_src():
    names = defined_names()
    found = recipe_identifiers(DOC.read_text())
    assert len(found) > 30  # the recipes do name things
    missing = sorted(found - names)
    assert not missing, f"docs/architecture.md's recipes name what src/ does not define: {missing}"


def test_a_drifted_name_is_caught():
    assert "_rk4_update" not in defined_names()
    assert "_rk4_update" in recipe_identifiers("## Recipes\nthe `_rk4_update` helper\n")
