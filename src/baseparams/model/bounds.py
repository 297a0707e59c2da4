"""Bounds on the magnitudes a robot file may hold, checked when the file is read.

A number far beyond any robot (``1e308`` in a joint origin) does not make the analysis wrong
in an obvious way: it overflows to inf inside products, makes an SVD fail to converge or a rank
decision run for minutes. The readers refuse such values at load time, in one line naming the
file, the element and the attribute:

* lengths (joint origins, centres of mass, anchors): ``|x| <= 1e6`` m;
* angles (``rpy``): ``|a| <= 1e6`` rad; axis components: ``|a| <= 1e6`` (then normalised);
* masses: ``m <= 1e9`` kg;
* inertia tensor entries: ``|I| <= 1e12`` kg m^2.
"""

from __future__ import annotations

import numpy as np

from ..errors import ModelError

#: largest length [m] (a joint origin, a centre of mass) accepted in a robot file
MAX_LENGTH = 1e6
#: largest angle [rad] (``rpy``) and axis component accepted
MAX_ANGLE = 1e6
#: largest mass [kg]
MAX_MASS = 1e9
#: largest inertia tensor entry [kg m^2]
MAX_INERTIA = 1e12

_BOUNDS = {"length": (MAX_LENGTH, "m"), "angle": (MAX_ANGLE, "rad"), "axis": (MAX_ANGLE, ""),
           "mass": (MAX_MASS, "kg"), "inertia": (MAX_INERTIA, "kg m^2")}


def check_magnitude(values, kind: str, what: str) -> None:
    """Refuse values beyond the bound of their kind (module doc).

    Parameters
    ----------
    values : array_like
        The numbers read (finite: non-finite values are the readers' own errors).
    kind : str
        ``length``, ``angle``, ``axis``, ``mass`` or ``inertia``.
    what : str
        The file, element and attribute, for the message.

    Raises
    ------
    ModelError
        ``WHAT: |v| = 1e+308 exceeds the bound 1e+06 m for a length``.
    """
    bound, unit = _BOUNDS[kind]
    v = np.abs(np.asarray(values, dtype=float))
    if v.size and not (v <= bound).all():  # NaN too (the ndarray method: called for every number read)
        worst = float(np.nanmax(v)) if np.any(np.isfinite(v) | np.isinf(v)) else float("nan")
        raise ModelError(f"{what}: |value| = {worst:.3g} exceeds the bound {bound:g}{' ' + unit if unit else ''} "
                         f"for {'an' if kind[0] in 'ai' else 'a'} {kind}; not a robot's number")
