"""One docstring style across the package: numpydoc, checked by numpydoc's own validator.

Every public function, class and method defined in ``baseparams`` (names without a leading
underscore, in the module that defines them) must have a docstring whose sections document every
parameter (``PR01``), name no parameter that does not exist (``PR02``), give each parameter a
description (``PR07``) and have a ``Returns`` (or ``Yields``) section when it returns a value
(``RT01``).  The summary-line rules are ruff's ``D`` rules with the numpy convention
(``pyproject.toml``).
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil

from numpydoc import validate as numpydoc_validate

import baseparams

#: numpydoc checks enforced (numpydoc.readthedocs.io, "Validation")
CHECKS = ("GL08", "PR01", "PR02", "PR07", "RT01")


def _public_objects():
    """Yield ``(qualified name, object)`` for every public function, class and method."""
    for info in pkgutil.walk_packages(baseparams.__path__, "baseparams."):
        module = importlib.import_module(info.name)
        for name, obj in vars(module).items():
            if name.startswith("_") or getattr(obj, "__module__", None) != module.__name__:
                continue
            if not (inspect.isfunction(obj) or inspect.isclass(obj)):
                continue
            yield f"{info.name}.{name}", obj
            if inspect.isclass(obj):
                for attr, member in vars(obj).items():
                    if not attr.startswith("_") and inspect.isfunction(member):
                        yield f"{info.name}.{name}.{attr}", member


def test_public_docstrings_follow_numpydoc():
    problems = []
    for qualname, _ in _public_objects():
        result = numpydoc_validate.validate(qualname)
        problems += [f"{qualname}: {code} {msg}" for code, msg in result["errors"] if code in CHECKS]
    assert not problems, f"{len(problems)} docstring problems:\n" + "\n".join(problems[:60])


def test_the_check_sees_the_package():
    names = {q for q, _ in _public_objects()}
    assert "baseparams.analysis.analyze" in names
    assert "baseparams.model.robot.Robot.parameters" in names
    assert len(names) > 150
