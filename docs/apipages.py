"""The API reference's pages, written from the package itself at every build (``docs/conf.py``).

Nothing is listed by hand: the *front door* is ``baseparams`` (its ``__all__``), the *public
faces* are the subpackages and modules ``dir(baseparams)`` names (each one's ``__all__``, or the
public names it defines), and the *internals* are every other module of the package, found by
walking it, so that a docstring's reference to a module behind a face resolves. A class a face
exports is documented there only (autodoc gives it its canonical name too), so it is not repeated
in its module's page. The pages go to ``reference/api/generated/`` (not tracked: ``.gitignore``).
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import shutil
import types
from pathlib import Path


def faces() -> list[str]:
    """The front door, then the documented subpackages and modules of ``dir(baseparams)``."""
    import baseparams

    subs = [n for n in dir(baseparams) if not n.startswith("_") and n not in baseparams.__all__
            and isinstance(getattr(baseparams, n), types.ModuleType)]
    return ["baseparams"] + [f"baseparams.{n}" for n in sorted(subs)]


def rooms(exclude: set[str]) -> list[str]:
    """Every other module of the package (the rooms behind the faces), in import-path order."""
    import baseparams

    names = [m.name for m in pkgutil.walk_packages(baseparams.__path__, "baseparams.")]
    return sorted(n for n in names if n not in exclude and n != "baseparams.__main__")


def _public(module: types.ModuleType) -> list[str]:
    """A face's names: its ``__all__``, else the public names it defines."""
    names = getattr(module, "__all__", None)
    if names is not None:
        return [n for n in names if not n.startswith("_")]
    return [n for n, obj in vars(module).items() if not n.startswith("_")
            and getattr(obj, "__module__", None) == module.__name__
            and (inspect.isclass(obj) or inspect.isfunction(obj))]


def _exported_classes(names: list[str]) -> dict[str, set[str]]:
    """Module -> classes documented on a face under another name (their canonical name's module)."""
    out: dict[str, set[str]] = {}
    for name in names:
        module = importlib.import_module(name)
        for attr in _public(module):
            obj = getattr(module, attr, None)
            if inspect.isclass(obj) and obj.__module__ != name:
                out.setdefault(obj.__module__, set()).add(obj.__qualname__)
    return out


def _title(text: str) -> str:
    return f"{text}\n{'=' * len(text)}\n\n"


def _face_page(name: str, seen: set[int]) -> str:
    """A face: its docstring, then each public name (a class a former face showed: not indexed again)."""
    module = importlib.import_module(name)
    head = _title(f"``{name}``") + f".. automodule:: {name}\n"
    head += "   :no-index:\n" if _shadowed(name) else ""
    if getattr(module, "__all__", None) is None:  # a module: what it defines
        return head + "   :members:\n   :undoc-members:\n\n"
    text = head + "   :no-members:\n\n"
    for attr in _public(module):
        obj = getattr(module, attr, None)
        if isinstance(obj, types.ModuleType):
            continue
        kind = "class" if inspect.isclass(obj) else "function" if callable(obj) else "data"
        text += f".. auto{kind}:: {name}.{attr}\n"
        if kind == "class":
            text += "   :members:\n" + ("   :no-index:\n" if id(obj) in seen else "")
            seen.add(id(obj))
        text += "\n"
    return text


def _shadowed(name: str) -> bool:
    """A module whose package's attribute of the same name is something else.

    ``baseparams.regressor`` is the front door's function, ``baseparams.workflow.identify`` the
    package's: the function keeps the name's entry, the module's own entry is not indexed (its
    members are). The module is imported first: a submodule nothing has imported yet is no
    attribute of its package, and is not shadowed.
    """
    parent, _, leaf = name.rpartition(".")
    if not parent:
        return False
    importlib.import_module(name)
    return not isinstance(getattr(importlib.import_module(parent), leaf, None), types.ModuleType)


def _members(name: str, skip: set[str]) -> list[tuple[str, str]]:
    """``(kind, name)`` of what ``automodule`` documents of a module, in source order.

    The classes and functions it defines (private ones too) and its data with a ``#:`` comment or a
    docstring.
    """
    from sphinx.pycode import ModuleAnalyzer

    module = importlib.import_module(name)
    analyzer = ModuleAnalyzer.for_module(name)
    documented = {attr for (owner, attr) in analyzer.find_attr_docs() if owner == ""}
    out = []
    for attr, obj in vars(module).items():
        if attr.startswith("__") or attr in skip:
            continue
        if inspect.isclass(obj) or inspect.isfunction(obj):
            if getattr(obj, "__module__", None) == name:
                out.append(("class" if inspect.isclass(obj) else "function", attr))
        elif attr in documented:
            out.append(("data", attr))
    order = analyzer.tagorder
    return sorted(out, key=lambda m: order.get(m[1], len(order)))


def _room_page(name: str, skip: set[str]) -> str:
    if _shadowed(name):  # the module's entry would collide with the function's: its members one by one
        text = _title(f"``{name}``") + f".. automodule:: {name}\n   :no-index:\n   :no-members:\n\n"
        text += f".. currentmodule:: {name}\n\n"
        for kind, attr in _members(name, skip):
            text += f".. auto{kind}:: {name}.{attr}\n"
            if kind == "class":
                text += "   :members:\n   :undoc-members:\n   :private-members:\n"
            text += "\n"
        return text
    text = (_title(f"``{name}``") + f".. automodule:: {name}\n   :members:\n   :undoc-members:\n"
            "   :private-members:\n   :ignore-module-all:\n")
    if skip:
        text += f"   :exclude-members: {', '.join(sorted(skip))}\n"
    return text + "\n"


def write_api_pages(folder: Path) -> dict[str, str]:
    """Write one page per face and per room into ``folder`` (emptied first).

    Returns
    -------
    dict
        The shadowed modules' pages (module -> document name, relative to the source folder), for
        the references to them.
    """
    shutil.rmtree(folder, ignore_errors=True)
    (folder / "internals").mkdir(parents=True)
    names = faces()
    exported = _exported_classes(names)
    seen: set[int] = set()
    for name in names:
        (folder / f"{name}.rst").write_text(_face_page(name, seen), encoding="utf-8")
    for name in rooms(set(names)):
        (folder / "internals" / f"{name}.rst").write_text(_room_page(name, exported.get(name, set())),
                                                          encoding="utf-8")
    docs = folder.relative_to(folder.parents[2]).as_posix()
    return {name: f"{docs}/{name}" if name in names else f"{docs}/internals/{name}"
            for name in [*names, *rooms(set(names))] if name != "baseparams" and _shadowed(name)}


def cli_parser():
    """``baseparams.cli.build_parser()`` with its help texts made literal for reStructuredText.

    sphinx-argparse reads help texts as reStructuredText, where ``q_<joint>`` would be a link and
    ``*`` or ``|`` markup: they are escaped, nothing else changes (the CLI reference's source).
    """
    import argparse
    import re

    from baseparams.cli import build_parser

    def escape(text):
        return re.sub(r"([_*|`\\])", r"\\\1", text) if isinstance(text, str) else text

    seen = set()

    def walk(parser):
        if id(parser) in seen:
            return
        seen.add(id(parser))
        parser.description, parser.epilog = escape(parser.description), escape(parser.epilog)
        for action in parser._actions:
            action.help = escape(action.help)
            if isinstance(action, argparse._SubParsersAction):
                for choice in action._choices_actions:
                    choice.help = escape(choice.help)
                for sub in action.choices.values():
                    walk(sub)

    parser = build_parser()
    walk(parser)
    return parser
