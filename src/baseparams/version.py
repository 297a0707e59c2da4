"""The package's version, written once: ``version`` in ``pyproject.toml``.

Read from the installed distribution's metadata (:func:`importlib.metadata.version`), or, for a
source tree that is not installed, from the ``pyproject.toml`` beside it. Looked up on first use
(the metadata scan costs ~20 ms): ``import baseparams`` does not pay for it.
"""

from __future__ import annotations

import functools
from pathlib import Path

#: what :func:`version` says when neither the metadata nor a ``pyproject.toml`` names the version
UNKNOWN = "0+unknown"


@functools.cache
def version() -> str:
    """The version of baseparams.

    Returns
    -------
    str
        The installed distribution's version, else the source tree's ``pyproject.toml`` one,
        else :data:`UNKNOWN`.
    """
    from importlib.metadata import PackageNotFoundError
    from importlib.metadata import version as installed

    try:
        return installed("baseparams")
    except PackageNotFoundError:
        pass
    pyproject = Path(__file__).resolve().parents[2] / "pyproject.toml"
    try:
        import tomllib

        project = tomllib.loads(pyproject.read_text(encoding="utf-8")).get("project", {})
    except (OSError, ValueError):
        return UNKNOWN
    return str(project["version"]) if project.get("name") == "baseparams" and "version" in project else UNKNOWN
