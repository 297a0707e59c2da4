"""Sphinx configuration of the baseparams documentation (``docs/``).

Built strictly, offline: ``sphinx-build -W --keep-going -n docs BUILD`` (warnings are errors;
``tests/test_docs.py`` and ``.ci/run``). The pages are Markdown (MyST); the API reference is
generated from the numpydoc docstrings (autodoc + autosummary + numpydoc), the CLI reference from
``baseparams.cli.build_parser`` (sphinx-argparse). No intersphinx: nothing is downloaded.
"""

from __future__ import annotations

import builtins
import re
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
# Python's own names (KeyboardInterrupt, SystemExit, ValueError, len, ...): the standard library is not linked either
_BUILTINS = sorted(n for n in dir(builtins) if not n.startswith("_"))
nitpick_ignore_regex = [("py:.*", rf"({'|'.join(_OUTSIDE)})(\..*)?"),
                        ("py:(func|class|obj|exc|meth|data)", rf"(builtins\.)?({'|'.join(_BUILTINS)})(\..*)?")]


def _lookup(path: str) -> str | None:
    """The canonical dotted name of what a dotted path names in Python, or None when nothing is there.

    A class or function met on the way is rebased on its own module (``baseparams.Robot.limits``
    -> ``baseparams.model.robot.Robot.limits``). An instance attribute (a dataclass field, an
    annotation, a slot, ``self.x = ...``) counts as existing.
    """
    import importlib
    import inspect

    parts = path.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        name = obj.__name__
        for k, attr in enumerate(parts[cut:]):
            owner = obj
            if hasattr(owner, attr):
                obj = getattr(owner, attr)
            elif k == len(parts[cut:]) - 1 and inspect.isclass(owner) and _declares(owner, attr):
                obj = None
            else:
                return None
            name = f"{name}.{attr}"
            if (inspect.isclass(obj) or inspect.isfunction(obj)) and hasattr(obj, "__qualname__"):
                name = f"{obj.__module__}.{obj.__qualname__}"
        return name
    return None


def _declares(cls, attr: str) -> bool:
    """Whether a class declares an instance attribute (field, annotation, slot, ``self.attr =``)."""
    import inspect

    for klass in cls.__mro__:
        declared = {*getattr(klass, "__annotations__", {}), *getattr(klass, "__slots__", ())}
        if attr in declared:
            return True
        try:
            source = inspect.getsource(klass)
        except (OSError, TypeError):
            continue
        if f"self.{attr} =" in source or f"self.{attr}:" in source or f'(self, "{attr}"' in source:
            return True
    return False


def _resolve_short(app, env, node, contnode):
    """A reference Sphinx does not find by itself: a short one, or one to an undocumented name.

    The name is looked up in Python from the referring class and module outwards, as a reader of
    the source would: when it exists, the link goes to its entry under its canonical name, or
    under the name a face documents it by, or else to its nearest documented owner (an instance
    attribute, a constant without a comment). Otherwise it is looked up by its ending among the
    documented objects, and linked when those nearest the referring module are one object. A name
    that exists nowhere is left to warn (``-n``: a broken reference fails the build).
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
    canonical = {}  # canonical name -> documented names
    for name in domain.objects:
        if name.rsplit(".", 1)[-1] == target.rsplit(".", 1)[-1]:
            canonical.setdefault(_lookup(name), []).append(name)
    # where the reference is written: the referring page's module and class, then the object whose
    # docstring holds it (``...: docstring of baseparams.base.regroup.base_parameters``), canonically
    places = [here]
    written = re.search(r"docstring of ([\w.]+)", node.source or "")
    if written:
        places.append(written.group(1))
    roots = []
    for place in places:
        for name in dict.fromkeys(filter(None, (place, _lookup(place) if place else None))):
            parts = name.split(".")
            roots += [parts[:cut] for cut in range(len(parts), -1, -1)]
    for root in roots:
        path = _lookup(".".join([*root, target]))
        if path is None:
            continue
        if path in domain.objects:
            return link(path)
        if canonical.get(path):
            return link(min(canonical[path], key=lambda n: (domain.objects[n].aliased, len(n))))
        parts = path.split(".")
        for k in range(len(parts) - 1, 0, -1):
            owner = ".".join(parts[:k])
            if owner in domain.objects:
                return link(owner)
            if canonical_owner := [n for n in domain.objects if n.endswith("." + parts[k - 1])
                                   and _lookup(n) == owner]:
                return link(min(canonical_owner, key=len))
    return None


def _rooms_out_of_the_contents(app, doctree) -> None:
    """The internals' objects stay out of the tables of contents (their pages keep every entry and anchor).

    Each page's navigation is resolved from every page's contents: with the ~3 000 functions, classes
    and methods behind the faces in them, that resolution was about 40 % of the build.
    """
    from sphinx import addnodes

    if app.env.docname.startswith("reference/api/generated/internals/"):
        for desc in doctree.findall(addnodes.desc):
            desc["no-contents-entry"] = True


def setup(app):
    """Write the API pages before Sphinx reads the sources; resolve short references."""
    app.connect("builder-inited", _generate)
    app.connect("missing-reference", _resolve_short)
    app.connect("doctree-read", _rooms_out_of_the_contents, priority=400)  # before the contents are collected
