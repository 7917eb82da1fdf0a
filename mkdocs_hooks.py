"""MkDocs hook for the docs site (``mkdocs.yml``, ``hooks:``).

The pages in ``docs/`` link to the repository's own files outside ``docs/``
(``../src/imdrive/kernels/engine.py``, ``../tests/package/test_layers.py``): such a link works
where the Markdown is read in the repository, but the site holds only ``docs/``, so MkDocs would
report it as a broken link. Before MkDocs reads a page, each such link whose target exists in the
repository becomes a link to that file on ``repo_url`` when one is configured, else the link
text followed by the path in the repository. A link whose target does not exist is left alone,
so ``mkdocs build --strict`` still fails on it; links inside ``docs/`` are MkDocs' own to check.

The docstrings cross-reference with Sphinx roles (``:func:`~imdrive.run.simulate.simulate```),
which Markdown renders as the role's name before the code. After a page is rendered, each such
reference becomes an optional mkdocs-autorefs cross-reference: a link where the target is on
the site's API reference, the plain name (``simulate``, for ``~``) where it is not.
"""

from __future__ import annotations

import re
from pathlib import Path

_LINK = re.compile(r"(?<!!)\[([^\]\n]+)\]\(([^)\s]+)\)")
_FENCE = re.compile(r"^\s*(```|~~~)")
_ROLE = re.compile(
    r":(?:py:)?(?:func|class|meth|mod|attr|data|exc|obj|const):<code>(~?)([^<]+)</code>"
)


def _outside_link(match: re.Match, page_dir: Path, docs: Path, root: Path, repo_url: str):
    text, target = match.groups()
    if target.startswith(("http://", "https://", "mailto:", "#")):
        return match.group(0)
    file = (page_dir / target.split("#")[0]).resolve()
    if file.is_relative_to(docs) or not file.is_relative_to(root) or not file.exists():
        return match.group(0)
    rel = file.relative_to(root).as_posix()
    if repo_url:
        kind = "tree" if file.is_dir() else "blob"
        return f"[{text}]({repo_url.rstrip('/')}/{kind}/main/{rel})"
    if rel in text or file.name in text:
        return text
    return f"{text} (`{rel}`)"


def on_page_markdown(markdown: str, page, config, files) -> str:
    """Rewrite the page's links to repository files outside ``docs/`` (see the module)."""
    page_dir = Path(page.file.abs_src_path).parent
    docs = Path(config["docs_dir"]).resolve()
    root = Path(config["config_file_path"]).resolve().parent
    repo_url = config.get("repo_url") or ""
    out, fenced = [], False
    for line in markdown.split("\n"):
        if _FENCE.match(line):
            fenced = not fenced
        elif not fenced:
            line = _LINK.sub(lambda m: _outside_link(m, page_dir, docs, root, repo_url), line)
        out.append(line)
    return "\n".join(out)


def _role(match: re.Match) -> str:
    short, target = match.groups()
    shown = target.rsplit(".", 1)[-1] if short else target
    return f'<autoref identifier="{target}" optional><code>{shown}</code></autoref>'


def on_page_content(html: str, page, config, files) -> str:
    """Turn the Sphinx roles of rendered docstrings into cross-references (see the module).

    Also drops the reStructuredText marker ``::`` before a literal block (Markdown shows the
    indented block as code without it).
    """
    html = html.replace("<p>::</p>", "").replace("::</p>", ":</p>")
    return _ROLE.sub(_role, html)
