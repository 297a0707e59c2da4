"""Model terms beyond rigid bodies and linear friction, kept when the data ask for them.

The rigid-body model (:mod:`baseparams.ident.model`) and the linear drive terms
(:mod:`baseparams.ident.drives`: rotor inertia, viscous, Coulomb, offset) are the linear core
``tau = A(q, dq, ddq) theta``. On a real arm what is left is model bias, not noise (the
Panda's residual repeats from one period of its trajectory to the next). Each module here is one
standard physical extension, with one interface (:class:`~baseparams.ident.terms.base.Term`):

* :mod:`~baseparams.ident.terms.dahl` - pre-sliding (Dahl) friction: the Coulomb term follows a
  state ``z_j`` integrated along the joint's path, ``dz/dq = (1 - z sgn dq) / delta_j``, instead
  of ``sign(dq_j)``; ``delta_j`` (a few mrad) by a search per joint;
* :mod:`~baseparams.ident.terms.tilt` - a mounting tilt: gravity's direction as two angles,
  acting on the standard parameters closest to the file's that have the identified base
  parameters (:func:`~baseparams.ident.select.complete`);
* :mod:`~baseparams.ident.terms.delay` - a delay per joint between the state and torque channels;
* :mod:`~baseparams.ident.terms.scale` - a torque-sensor scale per joint (one joint fixed to 1).

The measured torque of joint ``j`` is modelled as ``s_j M_j(t - d_j)`` with ``M = A theta`` (Dahl's
state in the Coulomb columns) plus the tilt's gravity torque. The nonlinear parameters are fitted
around the linear fit by Gauss-Newton (tilt, delay, scale: each step one weighted least-squares
problem with their linearised columns) and a grid search (Dahl's ``delta``), on the filtered,
decimated rows the linear fit uses (:mod:`~baseparams.ident.terms.fit`). Which terms are kept is
decided by blocked cross-validation on the training span only
(:func:`~baseparams.ident.terms.fit.select_terms`; several recordings: each recording one fold, its rows
from its own filter, grid and positions, :meth:`~baseparams.ident.terms.base.TermContext.stacked`): a term
stays when it lowers the held-out error of the training blocks by more than
:data:`~baseparams.ident.terms.fit.KEEP_GAIN`; the report lists every term kept or rejected with
its cross-validated figure, values and standard deviations.
"""

from __future__ import annotations

from .base import Term, TermContext
from .registry import TERMS, make_term

__all__ = ["TERMS", "Term", "TermContext", "make_term"]
