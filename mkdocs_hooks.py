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

The gallery (:func:`on_files`): each example notebook ``docs/examples/*.ipynb`` is executed
(nbclient, a fresh kernel with the inline backend) and added to the site as a Markdown page
``examples/<name>.md`` with its outputs, its figures as PNG files beside it. This is plain
Markdown through MkDocs' own pipeline, so ``--strict`` checks the pages like any other, and
nothing is fetched from the network (mkdocs-jupyter would add nbconvert, a JupyterLab theme and
its own HTML to the build). An executed notebook is kept in ``.cache/gallery`` under a hash of
the notebook and of the package's source, so the site is rebuilt without executing again until
one of them changes; the notebooks' tests (``tests/docs/test_docs_site.py``, run before its build)
fill the same cache.
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
    docs = Path(config["docs_dir"]).resolve()
    # a generated page (the gallery) sits where its source would
    page_dir = Path(page.file.abs_src_path or docs / page.file.src_uri).parent
    root = Path(config["config_file_path"]).resolve().parent
    repo_url = config.get("repo_url") or ""
    gallery = page.file.abs_src_path is not None  # a written page, not a gallery page

    def link(m: re.Match) -> str:
        return _gallery_link(m, page_dir, docs) if gallery else m.group(0)

    out, fenced = [], False
    for line in markdown.split("\n"):
        if _FENCE.match(line):
            fenced = not fenced
        elif not fenced:
            line = _LINK.sub(lambda m: _outside_link(m, page_dir, docs, root, repo_url), line)
            line = _LINK.sub(link, line)
        out.append(line)
    return "\n".join(out)


def _gallery_link(match: re.Match, page_dir: Path, docs: Path) -> str:
    """A link to an example notebook leads to its gallery page on the site (the page links
    the notebook itself); in the repository it leads to the notebook."""
    text, target = match.groups()
    path, _, anchor = target.partition("#")
    file = (page_dir / path).resolve()
    if not path.endswith(".ipynb") or file.parent != (docs / EXAMPLES).resolve():
        return match.group(0)
    page = path[: -len(".ipynb")] + ".md"
    return f"[{text}]({page}{'#' + anchor if anchor else ''})"


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


# --------------------------------------------------------------------------------------------
# the gallery: the example notebooks, executed, as pages with their figures

#: the example notebooks (each becomes ``examples/<stem>.md`` on the site, with its figures)
EXAMPLES = "examples"
#: executed notebooks, keyed by a hash of the notebook and of the package's source
GALLERY_CACHE = Path(__file__).resolve().parent / ".cache" / "gallery"
_ANSI = re.compile(r"\x1b\[[0-9;]*[A-Za-z]")


def _source_hash(notebook: Path) -> str:
    import hashlib

    root = Path(__file__).resolve().parent
    h = hashlib.sha256(notebook.read_bytes())
    for p in sorted((root / "src" / "imdrive").rglob("*")):
        if p.suffix in (".py", ".toml") and "__pycache__" not in p.parts:
            h.update(p.relative_to(root).as_posix().encode())
            h.update(p.read_bytes())
    return h.hexdigest()[:20]


#: where each notebook runs: an empty folder per notebook, at the same path at every run
NOTEBOOK_RUNS = GALLERY_CACHE.parent / "notebook-runs"


def execute_notebook(notebook: Path, timeout: int = 300):
    """The notebook executed in a fresh kernel (``nbclient``), in an empty folder of its own.

    The kernel imports this checkout's package (``src`` first on ``PYTHONPATH``) and uses the
    inline matplotlib backend, as Jupyter does. The folder (``.cache/notebook-runs/<name>``)
    is emptied before and removed after, but its path stays the same from run to run: a
    plug-in the notebook writes there (``06-own-estimator``'s ``my_estimator.py``) is imported
    under a name made from its path, and its compiled drive is cached under that name, so a
    temporary folder compiled it again at every execution (85 s on 2 cores).
    """
    import os
    import shutil
    import subprocess
    import tempfile

    import nbclient
    import nbformat

    src = str(Path(__file__).resolve().parent / "src")
    env_path = os.environ.get("PYTHONPATH")
    os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [src, env_path]))
    saved_backend = os.environ.pop("MPLBACKEND", None)  # the kernel picks the inline backend
    try:
        nb = nbformat.read(notebook, as_version=4)
        work = NOTEBOOK_RUNS / notebook.stem
        shutil.rmtree(work, ignore_errors=True)
        work.mkdir(parents=True)
        # the kernel's sockets in a short temporary path (a socket's path has ~100 bytes)
        with tempfile.TemporaryDirectory() as tmp:
            km = None
            if os.name == "posix":  # local sockets: no kernel on TCP (and no warning about it)
                from jupyter_client.manager import KernelManager

                km = KernelManager(kernel_name="python3", transport="ipc", ip=f"{tmp}/kernel")
            client = nbclient.NotebookClient(
                nb,
                km=km,
                timeout=timeout,
                kernel_name="python3",
                resources={"metadata": {"path": str(work)}},
            )
            # the kernel's own log (on shutdown: "Parent appears to have exited") is not the
            # notebook's output, and would read as a warning of the site's build
            client.execute(stderr=subprocess.DEVNULL)
    finally:
        shutil.rmtree(NOTEBOOK_RUNS / notebook.stem, ignore_errors=True)
        if env_path is None:
            os.environ.pop("PYTHONPATH", None)
        else:
            os.environ["PYTHONPATH"] = env_path
        if saved_backend is not None:
            os.environ["MPLBACKEND"] = saved_backend
    return nb


def cache_executed(notebook: Path, nb) -> Path:
    """Store an executed notebook where :func:`executed_notebook` finds it."""
    import nbformat

    GALLERY_CACHE.mkdir(parents=True, exist_ok=True)
    path = GALLERY_CACHE / f"{notebook.stem}-{_source_hash(notebook)}.ipynb"
    for old in GALLERY_CACHE.glob(f"{notebook.stem}-*.ipynb"):
        old.unlink()
    nbformat.write(nb, path)
    return path


def executed_notebook(notebook: Path):
    """The executed notebook: from the cache when neither it nor the package changed."""
    import nbformat

    cached = GALLERY_CACHE / f"{notebook.stem}-{_source_hash(notebook)}.ipynb"
    if cached.exists():
        return nbformat.read(cached, as_version=4)
    nb = execute_notebook(notebook)
    cache_executed(notebook, nb)
    return nb


def _fence(text: str, lang: str = "text") -> list[str]:
    text = _ANSI.sub("", text).rstrip("\n")
    return [f"```{lang}", text, "```", ""]


def notebook_markdown(notebook: Path, nb) -> tuple[str, dict[str, bytes]]:
    """An executed notebook as a Markdown page and its images (name -> PNG bytes).

    Markdown cells as they are, code cells as Python blocks, then their outputs: images as
    PNG files beside the page, HTML (tables) as it is, text in a plain block.
    """
    import base64

    stem = notebook.stem
    lines: list[str] = []
    images: dict[str, bytes] = {}
    for k, cell in enumerate(nb.cells):
        if cell.cell_type == "markdown":
            lines += [cell.source, ""]
            if k == 0:
                lines += [
                    f"*Executed when the site was built; download "
                    f"[{notebook.name}]({notebook.name}) to run it yourself.*",
                    "",
                ]
            continue
        if cell.cell_type != "code":
            continue
        lines += _fence(cell.source, "python")
        for out in cell.get("outputs", []):
            kind = out.get("output_type")
            if kind == "stream":
                lines += _fence(out.get("text", ""))
            elif kind == "error":
                lines += _fence("\n".join(out.get("traceback", [])))
            elif kind in ("execute_result", "display_data"):
                data = out.get("data", {})
                if "image/png" in data:
                    name = f"{stem}-{len(images) + 1}.png"
                    images[name] = base64.b64decode(data["image/png"])
                    lines += [f"![figure {len(images)} of {stem}]({name})", ""]
                elif "text/html" in data:
                    html = data["text/html"]
                    lines += ['<div class="nb-output" markdown="0">', html, "</div>", ""]
                elif "text/plain" in data:
                    lines += _fence(data["text/plain"])
    return "\n".join(lines), images


def on_files(files, config):
    """Add the gallery: each example notebook executed, as a page with its figures."""
    from mkdocs.structure.files import File

    docs = Path(config["docs_dir"])
    for notebook in sorted((docs / EXAMPLES).glob("*.ipynb")):
        text, images = notebook_markdown(notebook, executed_notebook(notebook))
        files.append(File.generated(config, f"{EXAMPLES}/{notebook.stem}.md", content=text))
        for name, data in images.items():
            files.append(File.generated(config, f"{EXAMPLES}/{name}", content=data))
    return files
