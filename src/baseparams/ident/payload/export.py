"""The robot with its identified payload as a fixed body on the link: a copy of the model file (URDF, MJCF).

URDF (:func:`payload_urdf`): the source file's text with one link and one fixed joint appended
(``<link name="LINK_payload">`` with the payload's ``<inertial>``: mass, centre of mass, inertia
about it in LINK's axes; ``<joint type="fixed">`` from LINK at its origin), the rest untouched.
MJCF (:func:`payload_mjcf`): the model read by MuJoCo (``MjSpec``; a URDF through MuJoCo's import)
with a body of the payload's inertia added under LINK's body, written by MuJoCo's writer.

Nothing is written unchecked: the written model is reloaded by MuJoCo, and its inverse dynamics
(``mj_inverse``; contacts, limits and dry friction off) minus the source's must be the payload's own
torques ``Y_L phi`` at random states to :data:`TOLERANCE` of their RMS (the written numbers' rounding);
a URDF is also read back by baseparams, whose merged link must be LINK plus the payload.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ...errors import BaseparamsError, ModelError

#: the largest relative RMS difference between MuJoCo's torques of the payload and the model's
TOLERANCE = 1e-4


def _payload_values(payload) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, centre of mass and inertia about it (LINK's frame) of a payload every quantity of which is known."""
    from .result import quantities

    q = quantities(payload.parameters)
    held = payload.options.prior is not None
    if len(payload.identified()) < 10 and not held:
        raise BaseparamsError("the motion does not identify every quantity of the payload and no prior holds the "
                              "others: nothing to write as a body (give a prior, or a richer motion)")
    if not (q[0] > 0 and np.all(np.isfinite(q))):
        raise BaseparamsError(f"the payload is not a body (mass {q[0]:.3g} kg): nothing written")
    xx, xy, xz, yy, yz, zz = q[4:]
    return float(q[0]), q[1:4], np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])


def _unique(names, base: str) -> str:
    name, k = base, 2
    while name in names:
        name, k = f"{base}_{k}", k + 1
    return name


def payload_urdf(payload, source, dest, inputs=()) -> list[str]:
    """Write the URDF ``source`` with the payload as a fixed link on its link (module docstring).

    Parameters
    ----------
    payload : Payload
        The identified payload (every quantity identified, or held at a prior).
    source : str or path
        The robot's URDF file (the one the payload's robot was read from).
    dest : str or path
        The file written (atomically; never an input).
    inputs : iterable of str or path
        Further input files ``dest`` must not overwrite.

    Returns
    -------
    list of str
        Notes: what was written and the checks' numbers.

    Raises
    ------
    BaseparamsError, ModelError
        A source that is not a URDF file, a payload that is not a body, a written file that fails a
        check (nothing written then).
    """
    from ...files import write_text
    from ...io import xmledit
    from ...io.sources import model_files

    source = Path(os.fspath(source))
    if source.suffix.lower() != ".urdf" or not source.is_file():
        raise BaseparamsError(f"--urdf writes the model file with the payload: it needs a URDF model file, got "
                              f"{source}")
    m, c, ic = _payload_values(payload)
    text = source.read_text(encoding="utf-8")
    root = xmledit.parse(text, str(source))
    names = {n.attrs.get("name") for n in root.findall("link") + root.findall("joint")}
    link = payload.link
    body = _unique(names, f"{link}_payload")
    joint = _unique(names, f"{body}_joint")
    num = "{:.17g}".format
    lines = [f"<!-- payload identified by baseparams: {m:.6g} kg on {link} -->",
             f'<link name="{body}">', "  <inertial>",
             f'    <origin xyz="{num(c[0])} {num(c[1])} {num(c[2])}" rpy="0 0 0"/>',
             f'    <mass value="{num(m)}"/>',
             f'    <inertia ixx="{num(ic[0, 0])}" ixy="{num(ic[0, 1])}" ixz="{num(ic[0, 2])}" iyy="{num(ic[1, 1])}" '
             f'iyz="{num(ic[1, 2])}" izz="{num(ic[2, 2])}"/>', "  </inertial>", "</link>",
             f'<joint name="{joint}" type="fixed">', f'  <parent link="{link}"/>', f'  <child link="{body}"/>',
             '  <origin xyz="0 0 0" rpy="0 0 0"/>', "</joint>"]
    edit = xmledit.Editor(text)
    edit.append(root, lines)
    new = edit.text()
    notes = _check_urdf_text(payload, new, source, dest)
    write_text(dest, new, [*model_files(source), *inputs], "--urdf")
    return [f"--urdf: {dest}: {source.name} with the payload as link {body!r} fixed to {link!r} (joint {joint!r})",
            *notes]


def _check_urdf_text(payload, text: str, source: Path, dest) -> list[str]:
    """Read the new URDF back (baseparams and MuJoCo, from a file beside ``source`` so its meshes resolve)."""
    import tempfile

    from ...io.urdf import load_urdf

    with tempfile.NamedTemporaryFile("w", suffix=".urdf", dir=source.parent, delete=False, encoding="utf-8") as fh:
        fh.write(text)
        tmp = Path(fh.name)
    try:
        robot = payload.model.robot
        back = load_urdf(tmp, gravity=robot.gravity)
        b = payload.model.body
        want = robot.N_body[b] + payload.pseudo_inertia()
        err = float(np.abs(back.N_body[b] - want).max() / max(np.abs(want).max(), 1e-300))
        if not err <= 1e-9:
            raise ModelError(f"{dest}: the written URDF read back gives link {payload.link!r} an inertia off by "
                             f"{err:.3g} (relative); not written")
        mj_err, states = _mujoco_check(payload, source, tmp, dest)
    finally:
        tmp.unlink(missing_ok=True)
    return [f"--urdf: read back by baseparams: {payload.link!r} is its own inertia plus the payload's (to {err:.2g})",
            f"--urdf: MuJoCo's mj_inverse of the written file minus the source's reproduces the payload's torques to "
            f"{mj_err:.2g} of their RMS on {states} random states"]


def _mujoco_check(payload, source: Path, written: Path, dest) -> tuple[float, int]:
    """MuJoCo's inverse dynamics of ``written`` minus ``source``'s against the payload's torques at random states."""
    from ...io.mjcf_write import mjcf_inverse
    from ...regressor.tp import projected_regressor
    from .model import link_frame_map

    robot = payload.model.robot
    rng = np.random.default_rng(0)
    q, dq, ddq = rng.uniform(-1.0, 1.0, (3, 32, robot.dof))
    p = np.zeros((10 * robot.n, 1))
    b = payload.model.body
    p[10 * b:10 * b + 10, 0] = link_frame_map(robot, b) @ payload.parameters
    want = projected_regressor(robot, q, dq, ddq, P=p)[:, :, 0]
    got = (mjcf_inverse(written, robot, q, dq, ddq, frictionloss=False, what=f"{dest} (as written)")
           - mjcf_inverse(source, robot, q, dq, ddq, frictionloss=False))
    err = float(np.sqrt(np.mean((got - want) ** 2)) / (np.sqrt(np.mean(want**2)) or 1.0))
    if not err <= TOLERANCE:
        raise ModelError(f"{dest}: MuJoCo's torques of the payload as written differ from the identified payload's "
                         f"by {err:.3g} of their RMS (> {TOLERANCE:g}); not written")
    return err, len(q)


def payload_mjcf(payload, source, dest, inputs=()) -> list[str]:
    """Write the model (MJCF, or a URDF through MuJoCo's import) as MJCF with the payload as a body on its link.

    Parameters
    ----------
    payload : Payload
        The identified payload (every quantity identified, or held at a prior).
    source : str or path
        The robot's MJCF (``.xml``) or URDF file.
    dest : str or path
        The ``.xml`` file written (atomically; never an input).
    inputs : iterable of str or path
        Further input files ``dest`` must not overwrite.

    Returns
    -------
    list of str
        Notes: what was written and the check's number.

    Raises
    ------
    BaseparamsError, ModelError
        Another source or suffix, a payload that is not a body, a model MuJoCo refuses, a written
        file that fails the check (nothing written then).
    """
    import mujoco as mj

    from ...files import atomic_path
    from ...io.sources import model_files

    source, dest = Path(os.fspath(source)), Path(os.fspath(dest))
    if source.suffix.lower() not in (".xml", ".urdf") or not source.is_file() or dest.suffix.lower() != ".xml":
        raise BaseparamsError(f"--mjcf writes the model as MJCF (.xml) with the payload: it needs an MJCF or URDF "
                              f"model file and a .xml output, got {source} and {dest}")
    m, c, ic = _payload_values(payload)
    try:
        spec = mj.MjSpec.from_file(str(source))
        spec.meshdir = str((source.parent / (spec.meshdir or "")).resolve())
        spec.texturedir = str((source.parent / (spec.texturedir or "")).resolve())
        model = spec.compile()
    except Exception as exc:  # noqa: BLE001 - MuJoCo raises ValueError and others
        raise ModelError(f"{source}: MuJoCo cannot load it ({str(exc).splitlines()[0] if str(exc) else exc})") from None
    frame = _mujoco_frame(mj, model, payload)
    rot, pos = frame[:3, :3], frame[:3, 3]
    parent = spec.body(payload.link)
    names = {b.name for b in spec.bodies}
    body = parent.add_body(name=_unique(names, f"{payload.link}_payload"), pos=[0.0, 0.0, 0.0])
    jc = rot @ ic @ rot.T
    spec.compiler.fusestatic = False  # the payload stays a body of its own when the file is loaded
    body.explicitinertial = 1
    body.mass, body.ipos = m, list(rot @ c + pos)
    body.fullinertia = [jc[0, 0], jc[1, 1], jc[2, 2], jc[0, 1], jc[0, 2], jc[1, 2]]
    try:
        spec.compile()
        text = spec.to_xml()
    except Exception as exc:  # noqa: BLE001
        raise ModelError(f"{dest}: MuJoCo refuses the model with the payload ({str(exc).splitlines()[0]}); "
                         f"not written") from None
    with atomic_path(dest, [*model_files(source), *inputs], "--mjcf") as tmp:
        tmp.write_text(text, encoding="utf-8")
        err, states = _mujoco_check(payload, source, tmp, dest)
    return [f"--mjcf: {dest}: {source.name} as MuJoCo reads it, with the payload as body {body.name!r} under "
            f"{payload.link!r}",
            f"--mjcf: reloaded by MuJoCo: its mj_inverse minus the source's reproduces the payload's torques to "
            f"{err:.2g} of their RMS on {states} random states"]


def _mujoco_frame(mj, model, payload) -> np.ndarray:
    """``(4, 4)``: LINK's frame (baseparams: its joint frame) in MuJoCo's body frame of LINK, at ``qpos0``."""
    data = mj.MjData(model)
    mj.mj_kinematics(model, data)
    try:
        bid = model.body(payload.link).id
    except KeyError:
        raise ModelError(f"MuJoCo has no body {payload.link!r} in this model") from None
    world = np.eye(4)
    world[:3, :3] = np.asarray(data.xmat[bid]).reshape(3, 3)
    world[:3, 3] = data.xpos[bid]
    return np.linalg.inv(world) @ payload.model.robot.M0[payload.model.body]
