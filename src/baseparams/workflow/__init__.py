"""The loop as functions: design an excitation, record it without a robot, identify, predict.

:func:`excite`, :func:`simulate`, :func:`identify` and :func:`predict` are ``baseparams.excite``,
``baseparams.simulate``, ``baseparams.identify`` and ``baseparams.predict`` (the front door
re-exports them) and the one implementation behind the commands of those names: the command line
parses its flags into these keywords (one keyword per flag) and prints. Each rule has one home
here, and both doors ask it:

* :mod:`~baseparams.workflow.inputs`: the arguments as the library's objects (a model as a Robot,
  a log as a JointLog, the input files no output may overwrite);
* :mod:`~baseparams.workflow.outputs`: the only suffix and output rules, and identify's writers;
* :mod:`~baseparams.workflow.excite`, :mod:`~baseparams.workflow.simulate`,
  :mod:`~baseparams.workflow.identify` (the streaming decision, a fleet of logs, ``predict``): each
  command's checks that need no model (``check_excite``, ``check_simulate``, ``plan_identify``,
  ``check_predict``, which the command line's preflight calls before the model loads) and its run;
* :mod:`~baseparams.workflow.payload`: :func:`identify_payload`, what a robot carries on a link
  (``check_payload``: its keywords' rules that need no model);
* :mod:`~baseparams.workflow.states`: the regressor of a states file.

Messages name options by their keywords (``holdout=``); the command line names them by their flags
(:mod:`baseparams.cli.parser`). The identification's options are one checked object
(:class:`~baseparams.ident.options.IdentOptions`, its defaults :data:`baseparams.arguments.IDENTIFY`'s).
"""

from .excite import excite
from .identify import identify, predict
from .payload import identify_payload
from .simulate import simulate

__all__ = ["excite", "identify", "identify_payload", "predict", "simulate"]
