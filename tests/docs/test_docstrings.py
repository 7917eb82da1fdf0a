"""Docstring completeness of the public API (numpydoc, with units).

The public API is what ``imdrive.__all__`` names plus the modules in :data:`PUBLIC_MODULES`
(exactly the modules the docs site's API reference renders, ``docs/api/*.md``; a test below
keeps the two lists equal). For every public function, class and public method or property
defined in imdrive and reachable from there:

* numpydoc's own validator (``numpydoc.validate.validate``, which parses the sections) must
  report none of :data:`CHECKS`: a docstring exists, it has a summary line, its Parameters
  section names every parameter of the signature and nothing else, each with a description,
  a function that returns a value has a Returns section, each entry described. The style
  checks (summary on one line, imperative mood, period at the end), and the See Also,
  Examples and extended-summary sections are not required: they say nothing a reader needs
  that the required sections miss, and a rule nobody keeps is noise.
* :func:`unit_problems`: every parameter or return value whose type is a real-valued number
  or array (``float``, ``complex``, ``ndarray``, ``array_like``) states its unit, either in its
  name (the package's convention: ``t_end_s``, ``speed_rpm``, ``R2_ohm``) or in its
  description (``[V]``, ``, rad/s``, ``in Hz``, ``10 A``), or says it is ``dimensionless`` /
  ``[-]`` / ``per unit`` / a percentage. A value of several quantities may state its unit by
  reference (``SI units``, ``in the column's unit``). Integers are counts, indices or seeds
  and are exempt.
"""

from __future__ import annotations

import importlib
import inspect
import re
from pathlib import Path

import numpydoc.validate as numpydoc_validate  # the test extra installs it: no skip
import pytest
from numpydoc.docscrape import NumpyDocString

import imdrive

ROOT = Path(__file__).resolve().parents[2]

#: the public modules besides ``imdrive.__all__``: each is rendered by the API reference
PUBLIC_MODULES = (
    "imdrive.errors",
    "imdrive.analysis.circuit",
    "imdrive.analysis.foc",
    "imdrive.stability",
    "imdrive.bench.protocol",
    "imdrive.bench.metrics",
    "imdrive.bench.report",
    "imdrive.sweep",
)

#: numpydoc validation codes that fail the test (numpydoc.validate.ERROR_MSGS has the texts)
CHECKS = (
    "GL08",  # the object has no docstring
    "SS01",  # no summary line
    "PR01",  # a parameter of the signature is not documented
    "PR02",  # a documented parameter is not in the signature
    "PR07",  # a parameter has no description
    "RT01",  # no Returns section though the function returns something
    "RT03",  # a return value has no description
)

# ------------------------------------------------------------------------------------------
# the unit rule

_NUMERIC_TYPE = re.compile(r"\b(float|complex|ndarray|array_like|array)\b")
_NAME_SUFFIX = re.compile(
    r"_(s|ms|us|Hz|rpm|rad|ohm|Nm|A|V|W|J|Wb|H|mH|kgm2|pct|degC|K|per_s|rad_s)$"
)
# a unit written in the description: a bracketed unit ([V], [rad/s], [-]) or a unit word
_BRACKET = re.compile(r"\[[^\]\s]{1,12}\]")
_WORDS = (
    r"dimensionless|per unit|p\.u\.|percent|%|rpm|Hz|kHz|rad/s|rad|ohms?|Ω|mH|µH|Wb|mWb|"
    r"N ?m|N·m|Nm|kg ?m²|kg ?m\^2|kgm2|°C|ms|µs|ns|kW|mA|mV|seconds?|volts?|amperes?|"
    r"henr(?:y|ies)|webers?|watts?|joules?|kelvin|radians?|SI units?|"
    # a unit stated by reference, for values of several quantities: "in the column's unit",
    # "each in the unit its name ends with", "in the unit of the quantity it drives"
    r"in (?:the|its|their) [\w' ]{0,40}?units?|each in the unit"
)
_WORD = re.compile(rf"(?<![\w/])({_WORDS})(?![\w/])")
# one-letter units (s, A, V, H, W, J, K) count only where they cannot be a word of the
# sentence: after a number, a comma or "in", or before a closing punctuation mark; "us"
# (microseconds, ASCII) only after a number
_LETTER = re.compile(
    r"(?:(?<=\d )|(?<=\d)|(?<=, )|(?<=\bin )|(?<=\())[sAVHWJK](?![\w/])"
    r"|(?<![\w/])[sAVHWJK](?=[,.;:)]|$)"
    r"|(?:(?<=\d )|(?<=\d))us(?![\w/])"
)


def states_a_unit(name: str, description: str) -> bool:
    """True if the name carries a unit suffix or the description states a unit."""
    names = [n.strip().lstrip("*") for n in name.split(",")]
    if names and all(_NAME_SUFFIX.search(n) for n in names if n):
        return True
    text = " ".join(description.split())
    return bool(_BRACKET.search(text) or _WORD.search(text) or _LETTER.search(text))


def unit_problems(obj) -> list[str]:
    """The numeric parameters and return values of ``obj``'s docstring that state no unit."""
    doc = inspect.getdoc(obj)
    if not doc:
        return []
    parsed = NumpyDocString(doc)
    problems = []
    for section in ("Parameters", "Returns", "Yields", "Attributes"):
        for item in parsed[section]:
            # Returns entries without a name come out with the type in ``name``
            name, kind = (item.name, item.type) if item.type else ("", item.name)
            if not _NUMERIC_TYPE.search(kind):
                continue
            if not states_a_unit(name, "\n".join(item.desc)):
                problems.append(f"{section}: {name or kind!r} states no unit")
    return problems


# ------------------------------------------------------------------------------------------
# the public API


def _defined_here(obj) -> bool:
    return getattr(obj, "__module__", "").startswith("imdrive")


def _members(module):
    names = getattr(module, "__all__", None)
    if names is None:
        names = [n for n in vars(module) if not n.startswith("_")]
    for n in names:
        obj = getattr(module, n, None)
        if (inspect.isfunction(obj) or inspect.isclass(obj)) and _defined_here(obj):
            if names is getattr(module, "__all__", None) or obj.__module__ == module.__name__:
                yield obj


def top_level(name: str):
    """``imdrive.<name>`` as the package defines it.

    Resolved through the package's table of lazy names, not ``getattr(imdrive, name)``:
    importing a deprecated 0.1 module path such as ``imdrive.simulate`` (as the compatibility
    tests do) binds that module over the package attribute of the same name.
    """
    lazy = getattr(imdrive, "_LAZY", {})
    if name in lazy:
        return getattr(importlib.import_module(lazy[name]), name)
    return getattr(imdrive, name)


def public_api() -> dict[str, object]:
    """Import path -> object for every public function, class, method and property."""
    roots = [top_level(n) for n in imdrive.__all__ if not n.startswith("__")]
    for m in PUBLIC_MODULES:
        roots.extend(_members(importlib.import_module(m)))
    found: dict[str, object] = {}
    for obj in roots:
        if not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        found[f"{obj.__module__}.{obj.__qualname__}"] = obj
        if inspect.isclass(obj):
            for k, v in vars(obj).items():
                if k.startswith("_"):
                    continue  # __init__ is documented by the class docstring
                if isinstance(v, (classmethod, staticmethod)):
                    v = v.__func__
                if inspect.isfunction(v) or isinstance(v, property):
                    found[f"{obj.__module__}.{obj.__qualname__}.{k}"] = v
    return found


API = public_api()


def _class_parameter_problems(cls) -> list[str]:
    """PR01/PR02 for a class: a dataclass's or model's fields may be listed as Attributes."""
    parsed = NumpyDocString(inspect.getdoc(cls) or "")
    documented = {
        n.strip().lstrip("*")
        for section in ("Parameters", "Attributes")
        for item in parsed[section]
        for n in item.name.split(",")
    }
    try:
        signature = inspect.signature(cls)
    except (TypeError, ValueError):
        return []
    params = {p for p in signature.parameters if not p.startswith("_")}
    missing = sorted(params - documented)
    listed = {n.strip().lstrip("*") for item in parsed["Parameters"] for n in item.name.split(",")}
    unknown = sorted(listed - set(signature.parameters))
    return [f"PR01: Parameters {missing} not documented"] * bool(missing) + [
        f"PR02: Unknown parameters {unknown}"
    ] * bool(unknown)


def numpydoc_problems(path: str) -> list[str]:
    """numpydoc's findings among :data:`CHECKS` for the object at the import ``path``.

    For a class, whose parameters numpydoc takes from ``__init__``, the fields of a dataclass
    or pydantic model count as documented when its Attributes section lists them (names
    starting with ``_`` are private).
    """
    result = numpydoc_validate.validate(path)
    obj = API.get(path)
    skip = {"PR01", "PR02"} if inspect.isclass(obj) else set()
    found = [f"{c}: {m}" for c, m in result["errors"] if c in CHECKS and c not in skip]
    return found + (_class_parameter_problems(obj) if skip else [])


def test_the_public_api_is_found():
    assert len(API) > 100
    for name in ("Scenario", "simulate", "simulate_batch", "SimulationResult", "BatchResult"):
        obj = top_level(name)
        assert callable(obj) and not inspect.ismodule(obj)
        assert f"{obj.__module__}.{obj.__qualname__}" in API
    assert "imdrive.run.result.SimulationResult.to_pandas" in API
    assert "imdrive.analysis.circuit.equivalent_circuit" in API


@pytest.mark.parametrize("path", sorted(API))
def test_public_docstring_is_complete_numpydoc(path):
    obj = API[path]
    if isinstance(obj, property):
        # numpydoc cannot import a property by path; a property needs a summary line
        doc = inspect.getdoc(obj)
        assert doc and doc.strip().splitlines()[0].strip(), f"{path}: no docstring"
        return
    problems = numpydoc_problems(path)
    assert not problems, f"{path}:\n  " + "\n  ".join(problems)


@pytest.mark.parametrize("path", sorted(p for p, o in API.items() if not isinstance(o, property)))
def test_numeric_parameters_state_their_unit(path):
    problems = unit_problems(API[path])
    assert not problems, f"{path}:\n  " + "\n  ".join(problems)


def test_api_reference_renders_exactly_the_public_modules():
    rendered = set()
    for page in (ROOT / "docs" / "api").glob("*.md"):
        rendered |= set(re.findall(r"^::: ([\w.]+)\s*$", page.read_text(), flags=re.M))
    modules = {r for r in rendered if r.rsplit(".", 1)[-1][:1].islower()}
    for name in imdrive.__all__:
        if name.startswith("__"):
            continue
        obj = top_level(name)
        assert f"{obj.__module__}.{obj.__qualname__}" in rendered or obj.__module__ in modules, (
            f"imdrive.{name} is not in the API reference (docs/api/)"
        )
    for m in PUBLIC_MODULES:
        assert m in rendered, f"{m} is in PUBLIC_MODULES but not in docs/api/"


# ------------------------------------------------------------------------------------------
# the checks can fail: deliberately broken docstrings


def _dummy_complete(Ts_s: float, gain: float, n: int = 1) -> float:
    """Scale a sample period.

    Parameters
    ----------
    Ts_s : float
        Sample period.
    gain : float
        Gain, dimensionless.
    n : int
        Repetitions.

    Returns
    -------
    float
        The scaled period, s.
    """
    return Ts_s * gain * n


def _dummy_broken(Ts: float, gain: float, n: int = 1) -> float:
    """Scale a sample period.

    Parameters
    ----------
    Ts : float
        A sample period.
    n : int
        Repetitions.
    """
    return Ts * gain * n


def test_a_complete_dummy_passes_both_checks():
    assert numpydoc_problems(f"{__name__}._dummy_complete") == []
    assert unit_problems(_dummy_complete) == []


def test_a_broken_dummy_fails_both_checks():
    codes = {p.split(":")[0] for p in numpydoc_problems(f"{__name__}._dummy_broken")}
    assert codes == {"PR01", "RT01"}  # ``gain`` undocumented, no Returns section
    assert unit_problems(_dummy_broken) == ["Parameters: 'Ts' states no unit"]


def test_a_missing_docstring_fails():
    def undocumented(x):
        return x

    undocumented.__module__ = __name__
    globals()["_undocumented"] = undocumented
    undocumented.__qualname__ = "_undocumented"
    try:
        assert [p[:4] for p in numpydoc_problems(f"{__name__}._undocumented")] == ["GL08"]
    finally:
        del globals()["_undocumented"]


@pytest.mark.parametrize(
    ("name", "description", "ok"),
    [
        ("Ts", "Sample period, s.", True),
        ("Ts", "Sample period [s].", True),
        ("Ts", "Sample period in ms.", True),
        ("i", "Current amplitude (A).", True),
        ("i", "Current of 10 A at most.", True),
        ("w", "Speed, rad/s.", True),
        ("ratio", "R2_hat/R2, dimensionless.", True),
        ("x", "Weight [-].", True),
        ("t_end_s", "End of the run.", True),
        ("Ts", "Sample period.", False),
        ("Ts", "A sample period.", False),
        ("x", "A value as a fraction.", False),
        ("speeds", "Speeds of the sweep.", False),
        ("Ts", "Sample period, 100 us by default.", True),
        ("Ts", "Sample period; lets us check it.", False),
        ("values", "The values, in the column's unit.", True),
        ("values", "The values, which have a unit.", False),
    ],
)
def test_the_unit_rule(name, description, ok):
    assert states_a_unit(name, description) is ok
