"""Sphinx configuration of the baseparams documentation (``docs/``).

Built strictly, offline: ``sphinx-build -W --keep-going -n docs BUILD`` (warnings are errors;
``tests/test_docs.py`` and ``.ci/run``). The pages are Markdown (MyST); the API reference is
generated from the numpydoc docstrings (autodoc + autosummary + numpydoc), the CLI reference from
``baseparams.cli.build_parser`` (sphinx-argparse). No intersphinx: nothing is downloaded.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from baseparams.version import version as _version  # noqa: E402

project = "baseparams"
author = "the baseparams developers"
copyright = "the baseparams developers, MIT licence"  # noqa: A001
release = _version()
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinxarg.ext",
]

source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
root_doc = "index"
exclude_patterns = ["_build", "conftest.py", "**/__pycache__"]

# ---------------------------------------------------------------- Markdown
myst_enable_extensions = ["colon_fence", "deflist", "dollarmath"]
myst_heading_anchors = 3

# ---------------------------------------------------------------- API reference
autodoc_typehints = "none"
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

# ---------------------------------------------------------------- output
html_theme = "furo"
html_title = f"baseparams {release}"
html_static_path: list[str] = []
# MathJax from the page's own copy would need a download at build time: the browser fetches it
# when a page with a formula is viewed; the build itself never touches the network


# ---------------------------------------------------------------- the API pages, generated at every build
sys.path.insert(0, str(Path(__file__).resolve().parent))
from apipages import write_api_pages  # noqa: E402

#: module -> its page, for the modules whose name a function of their package shadows (filled at build)
_MODULE_PAGES: dict[str, str] = {}


def _generate(app) -> None:
    _MODULE_PAGES.update(write_api_pages(Path(app.srcdir) / "reference" / "api" / "generated"))


# references into other projects' documentation: no intersphinx (nothing is downloaded), so the
# standard library's and the dependencies' names are not checked
_OUTSIDE = ("numpy", "np", "scipy", "ast", "os", "enum", "importlib", "tomllib", "typing", "collections", "pathlib",
            "dataclasses", "argparse", "zipfile", "io", "json", "math", "warnings", "dask", "distributed", "cvxpy",
            "clarabel", "sympy", "mujoco", "pinocchio", "pyarrow", "matplotlib", "rosbags", "numba", "xacro", "pandas")
nitpick_ignore_regex = [("py:.*", rf"({'|'.join(_OUTSIDE)})(\..*)?"),
                        ("py:(func|class|obj)", r"(repr|str|int|float|bool|dict|list|tuple|object|Exception)")]


def _lookup(path: str):
    """The Python object a dotted path names, or None.

    An instance attribute (``self.x = ...``, a dataclass field, an annotation, a slot) counts as
    existing and gives its class.
    """
    import importlib
    import inspect

    parts = path.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for k, attr in enumerate(parts[cut:]):
            if hasattr(obj, attr):
                obj = getattr(obj, attr)
                continue
            last = k == len(parts[cut:]) - 1
            if last and inspect.isclass(obj):
                declared = {*getattr(obj, "__annotations__", {}), *getattr(obj, "__dataclass_fields__", {}),
                            *getattr(obj, "__slots__", ())}
                try:
                    source = inspect.getsource(obj)
                except (OSError, TypeError):
                    source = ""
                if attr in declared or f"self.{attr} =" in source or f"self.{attr}:" in source:
                    return obj
            return None
        return obj
    return None


def _resolve_short(app, env, node, contnode):
    """A reference Sphinx does not find by itself: a short one, or one to an undocumented name.

    The name is looked up in Python from the referring class and module outwards (as a reader of
    the source would): when it exists, the link goes to its entry, or to the entry of the same
    object under another name (a class or function a face re-exports), or else to its nearest
    documented owner (an instance attribute, a constant without a comment). Otherwise it is looked
    up by its ending among the documented objects, and linked when the nearest is one object. A
    name that exists nowhere is left to warn (``-n``: a broken reference fails the build).
    """
    if node.get("refdomain") != "py":
        return None
    from sphinx.util.nodes import make_refnode

    domain = env.get_domain("py")
    target = node["reftarget"].lstrip("~.")
    here = ".".join(filter(None, (node.get("py:module"), node.get("py:class"))))

    def link(name: str):
        entry = domain.objects[name]
        return make_refnode(app.builder, node["refdoc"], entry.docname, entry.node_id, contnode, name)

    if node.get("reftype") == "mod" and target in _MODULE_PAGES:  # a module a function's name shadows
        return make_refnode(app.builder, node["refdoc"], _MODULE_PAGES[target], None, contnode, target)
    scopes = here.split(".") if here else []
    for cut in range(len(scopes), -1, -1):
        path = ".".join([*scopes[:cut], target])
        obj = _lookup(path)
        if obj is None:
            continue
        if path in domain.objects:
            return link(path)
        leaf = path.rsplit(".", 1)[-1]
        same = sorted((n for n in domain.objects if n.rsplit(".", 1)[-1] == leaf and _lookup(n) is obj),
                      key=lambda n: (domain.objects[n].aliased, len(n)))
        if same:
            return link(same[0])
        parts = path.split(".")
        for k in range(len(parts) - 1, 0, -1):
            if ".".join(parts[:k]) in domain.objects:
                return link(".".join(parts[:k]))

    def nearness(name: str) -> int:
        common = 0
        for a, b in zip(name.split("."), here.split(".")):
            if a != b:
                break
            common += 1
        return common

    hits = [name for name in domain.objects if name.endswith("." + target)]
    best = max((nearness(h) for h in hits), default=-1)
    nearest = sorted((h for h in hits if nearness(h) == best), key=lambda h: domain.objects[h].aliased)
    if nearest and len({(domain.objects[h].docname, domain.objects[h].node_id) for h in nearest}) == 1:
        return link(nearest[0])
    return None


def setup(app):
    """Write the API pages before Sphinx reads the sources; resolve short references."""
    app.connect("builder-inited", _generate)
    app.connect("missing-reference", _resolve_short)
