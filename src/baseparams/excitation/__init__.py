"""Excitation trajectories: the motion that identifies every base parameter, within the limits.

A finite Fourier series per designed coordinate (Swevers et al. 1997): the joints of a tree, or a
robot with loops' actuated coordinates, the passive ones following from the loop closure,

``q_j(t) = q0_j + sum_l a_lj / (l w) sin(l w t) - b_lj / (l w) cos(l w t)``, ``w = 2 pi f``,

so ``dq_j = sum_l a_lj cos(l w t) + b_lj sin(l w t)`` and ``ddq_j = sum_l l w (b_lj cos - a_lj sin)``
(exact derivatives, period ``T = 1 / f``). **Rest at both ends**: ``dq(0) = sum_l a_l = 0`` and
``ddq(0) = w sum_l l b_l = 0`` are imposed by eliminating the first harmonic's coefficients,
``a_1 = -sum_{l>=2} a_l`` and ``b_1 = -sum_{l>=2} l b_l``; the series is periodic, so the motion is
at rest at ``t = T`` too and can be repeated. The free variables per coordinate are the offset
``q0`` and ``a_l, b_l`` for ``l = 2..L`` (:func:`fourier_basis`).

Criterion, on the identification model's regressor (:class:`~baseparams.ident.IdentModel`:
the certified base parameters, and the drive columns when asked), evaluated on a coarse grid of
one period (``grid`` samples): ``cond``, the condition number of the column-scaled stacked
regressor (minimised as ``log cond``), or ``logdet``, D-optimality, ``log det`` of the
information matrix per sample (maximised; independent of the parameters' units up to a
constant). ``cond`` balances the columns whatever their size (it does not reward a larger
motion); ``logdet`` rewards information, hence smaller standard deviations under noise. The
gradient is exact up to finite differences of the regressor per state column (the regressor of a
sample depends on that sample's state only, so ``3 m + 1`` batched evaluations give every
sample's derivative at once; at ``|dq| < 2e-6`` the velocity derivative is dropped: Coulomb
friction's ``sign(dq)`` jumps there).

Constraints, on the same grid: position, velocity and acceleration limits (linear in the
coefficients; every :data:`.problem.LIMIT_STRIDE`-th sample), optionally the torques of the model's own
(prior) parameters within the effort limits and, for loops, ``cond(J_p) <= cond_max`` at every
sample (which keeps the motion inside the workspace, away from singularities, and on the
reference assembly mode reached by continuation from q = 0). SLSQP from several seeded random
starts; the best design is then sampled at the controller's rate, each coordinate's oscillation
scaled down if a sample there exceeds a limit, and checked (loops: every sample closed with
``cond(J_p) <= cond_max``).

One home per job: :mod:`.fourier` (the series and its rest conditions), :mod:`.limits` (the
limits per designed coordinate, a loop robot's ``cond(J_p)`` bound), :mod:`.problem` (one design:
model, grid, margins, options, keep-out), :mod:`.criterion` (``cond`` / ``logdet`` and their
gradients), :mod:`.constraints` (the constraint rows, the cached evaluator), :mod:`.diagnose`
(which constraint binds, said to a user), :mod:`.design` (the optimiser: :func:`design_excitation`,
:func:`random_excitation`) and :mod:`.result` (:class:`Excitation`, saved and read back:
:func:`read_trajectory`). ``baseparams.excite(...)`` is the front door (the CLI's ``baseparams excite``).
"""

from .criterion import criterion_terms, trajectory_criterion
from .design import design_excitation, random_excitation
from .fourier import coefficients, fourier_basis, free_coefficients, rest_map
from .limits import design_coordinates, excitation_limits, loop_bound
from .problem import CRITERIA
from .result import Excitation, read_trajectory

__all__ = ["CRITERIA", "Excitation", "coefficients", "criterion_terms", "design_coordinates", "design_excitation",
           "excitation_limits", "fourier_basis", "free_coefficients", "loop_bound", "random_excitation",
           "read_trajectory", "rest_map", "trajectory_criterion"]
