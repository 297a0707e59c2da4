"""Writing identified parameters into a copy of an MJCF model, through MuJoCo's ``MjSpec``.

:func:`write_mjcf` reads the model with MuJoCo (``MjSpec.from_file``, as :func:`~baseparams.io.mjcf.load_mjcf`
reads it), sets every moving body's ``<inertial>`` (mass, centre of mass ``pos``, principal axes
``quat`` and ``diaginertia``) and every joint's ``armature`` (rotor inertia ``Ia``), ``damping``
(viscous friction ``Fv``) and ``frictionloss`` (Coulomb friction ``Fc``), and writes the model with
MuJoCo's own writer (``MjSpec.to_xml``). Bodies welded to a moving body (no joint of their own:
the reader merges their inertia into it) get zero mass, as :func:`~baseparams.io.urdf.write_urdf`
does for links merged by fixed joints: the moving body carries the identified inertia of the
whole rigid group. Bodies welded to the world keep their values. A URDF source is read by MuJoCo's
URDF import (links fixed to their parent fused into it, visual geoms dropped, as MuJoCo imports
URDF) and written as MJCF.

Frames: the identified parameters are in the world frame at ``qpos0`` (``paper`` convention) or in
each body's link frame (baseparams: the MuJoCo body frame moved to its joint's anchor); they are
expressed in the MuJoCo body frame (``body_xpos``, ``body_xmat`` at ``qpos0``) before writing.

Nothing is written unchecked: the written text is reloaded by MuJoCo and its inverse dynamics
(``mj_inverse``; contacts, joint limits, equalities and springs disabled, which are not part of the
identified model) must reproduce the parameters' own generalized forces (rigid body, armature,
damping; for an identification, :func:`baseparams.ident.export.identified_mjcf`, its own prediction of
them, its base-parameter regressor times its ``theta``) to :data:`TOLERANCE` relative RMS, or nothing
is written. MuJoCo's writer prints six significant digits (``%g``), so the file's numbers (poses too,
which MuJoCo rewrites as it compiled them) carry relative rounding up to ``5e-7``; the torques they give differ from the
parameters' at ~1e-6 of their RMS on the test robots. A wrong frame, sign or unit errs by
percents.

MuJoCo's ``frictionloss`` is not ``Fc sign(dq)``: it is a soft dry-friction constraint whose force
is bounded by ``Fc`` and, in inverse dynamics, follows from the acceleration and the velocity
through the constraint's impedance (``solreffriction``, ``solimpfriction``): it reaches ``Fc`` only
away from zero velocity and is smooth through it. The difference on the checked states is
reported in the notes, not refused. Torque offsets ``Fo`` have no MJCF joint attribute: they are
left out and named in the notes.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..errors import BaseparamsError, ModelError
from ..files import atomic_path
from ..model import inertia as I
from ..model.robot import Robot
from . import xmledit
from .mjcf import compiled_spec, one_line

#: largest relative RMS difference between the written model's ``mj_inverse`` and the parameters'
#: own generalized forces (rigid body, armature, damping); see the module doc
TOLERANCE = 1e-4

#: drive kind -> (MJCF joint attribute, what it is)
_JOINT_ATTRS = {"Ia": ("armature", "rotor inertia"), "Fv": ("damping", "viscous friction"),
                "Fc": ("frictionloss", "Coulomb friction")}


def write_mjcf(source: str | Path, dest: str | Path, robot: Robot, params, convention: str, *,
               drives: dict | None = None, states=None, expected=None, inputs=(),
               tolerance: float = TOLERANCE, base_rotation=None) -> list[str]:
    """Write ``source`` to ``dest`` with the identified inertias and drive terms (module doc).

    Parameters
    ----------
    source : str or Path
        The MJCF file ``robot`` was read from, or a URDF file (read by MuJoCo's URDF import; the
        output is MJCF).
    dest : str or Path
        The file written (atomically; never one of ``source`` and ``inputs``).
    robot : Robot
        The robot :func:`~baseparams.io.mjcf.load_mjcf` (or ``load_urdf``) read from ``source`` (``n`` moving bodies,
        each on one hinge or slide joint; fixed base, no loops).
    params : array_like, shape ``(10 n,)``
        The inertial parameters, ten per body, in ``convention``.
    convention : str
        Their convention: ``paper`` in the world frame at ``qpos0``, the others in each body's link
        frame (:class:`~baseparams.enums.Convention`).
    drives : dict, optional
        ``{joint name: {"Ia", "Fv", "Fc", "Fo": float or None}}`` in the joint's units. A kind
        missing or None was not identified: the joint's attribute is set to zero (the identified
        model has no such term), with a note when the source's was not.
    states : tuple of ndarray, optional
        ``(q, dq, ddq)``, each ``(S, robot.dof)`` in the robot's coordinates (``q`` from
        ``qpos0``): where the written model is checked. Default: 64 seeded random states.
    expected : array_like, shape ``(S, robot.dof)``, optional
        The generalized forces the written model must give at ``states`` without dry friction
        and offsets (e.g. an identification's own prediction of its rigid-body, rotor-inertia and
        viscous terms). Default: the TP regressor times ``params`` plus ``Ia ddq + Fv dq``.
    inputs : iterable of str or Path
        Further input files ``dest`` must not overwrite (the log, ...).
    tolerance : float
        Largest relative RMS difference accepted by the check (:data:`TOLERANCE`).
    base_rotation : array_like, shape ``(3, 3)``, optional
        A rotation of the robot in the world (a mounting tilt,
        :meth:`baseparams.ident.terms.tilt.Tilt.base_rotation`): every body on the world body is
        rotated about the world's origin (``expected`` must include the tilted gravity's torques).

    Returns
    -------
    list of str
        Notes: what was written, changed in the compiler options, left out, and the check's numbers.

    Raises
    ------
    ModelError
        A robot this writer does not handle, a body MJCF cannot represent, a negative drive
        term, or a written model that fails the check (nothing is written then).
    BaseparamsError
        ``dest`` is an input or cannot be written.
    """
    import mujoco as mj

    from .sources import check_urdf_meshes, model_files

    source, dest = Path(source), Path(dest)
    check_mjcf_robot(robot, source)
    urdf = source.suffix.lower() == ".urdf"
    if urdf:  # MuJoCo's URDF import reads the meshes: never a FIFO or a device
        check_urdf_meshes(source)
    try:
        spec, model, notes = compiled_spec(source)
    except ModelError as exc:
        raise ModelError(f"{exc}{' (MuJoCo imports this URDF; --urdf writes the URDF itself)' if urdf else ''}") \
            from None
    notes = [f"--mjcf: {n}" for n in notes] + (["--mjcf: the copy is written without the stripped asset files and "
                                                 "geoms (MuJoCo's writer compiles the model)"] if notes else [])
    ids = _moving_ids(model, robot, source)
    n_body = _body_frame_inertias(mj, model, robot, params, convention, ids)
    drives = drives or {}
    unknown = sorted(set(drives) - set(robot.joint_names))
    if unknown:
        raise ModelError(f"{source}: drive terms of joints {unknown[:5]} that are not in the robot")
    if urdf:
        notes.append(f"--mjcf: {source.name} is a URDF: written as MuJoCo imports it (links fixed to their parent "
                     f"fused into it, visual geoms dropped)")
    notes += _compiler_options(mj, spec)
    by_id = {b.id: b for b in spec.bodies}
    for i, name in enumerate(robot.names):
        _set_inertial(by_id[ids[i]], n_body[i], f"{dest}: <body name={name!r}>")
    notes += _zero_welded(by_id, set(ids))
    notes += _set_joints(by_id, robot, ids, drives, source)
    check_robot = robot
    if base_rotation is not None:
        rot = np.asarray(base_rotation, dtype=float)
        notes += _rotate_base(mj, spec, rot)
        check_robot = replace(robot, gravity=rot.T @ robot.gravity)
    text = _relocate_assets(_to_xml(spec, dest), spec, source, dest)
    with atomic_path(dest, inputs=[*model_files(source), *inputs], what="--mjcf") as tmp:
        tmp.write_text(text, encoding="utf-8")
        notes += _check(tmp, dest, robot, (params, convention, drives), states, expected, tolerance, check_robot)
    return notes


def check_mjcf_robot(robot: Robot, source) -> None:
    """Refuse what the writer does not handle: loops, couplings, a floating base, multi-joint bodies.

    Called before any fit too (:func:`baseparams.identify` with ``mjcf=``): the robot says it.

    Parameters
    ----------
    robot : Robot
        The robot the model file describes.
    source : str or Path
        The model file, for messages.

    Raises
    ------
    ModelError
        One line naming the body or the robot and what the writer does not handle.
    """
    if robot.has_loops or robot.couplings:
        raise ModelError(f"{source}: --mjcf writes tree robots; robot {robot.name!r} has closed loops or coupled "
                         f"joints (equalities), whose MuJoCo inverse dynamics is not the identified model's")
    if robot.floating:
        raise ModelError(f"{source}: --mjcf writes fixed-base robots; robot {robot.name!r} has a floating base")
    for name, jt in zip(robot.names, robot.jtype):
        if jt not in ("R", "P"):
            raise ModelError(f"{source}: body {name!r}: --mjcf writes bodies on one hinge or slide joint, not a "
                             f"{jt} joint")


def _moving_ids(model, robot: Robot, source: Path) -> list[int]:
    """The MuJoCo body index of each of the robot's bodies (its name, or ``body<id>`` as the reader names it)."""
    names = {model.body(i).name or f"body{i}": i for i in range(1, model.nbody)}
    missing = [b for b in robot.names if b not in names]
    if missing:
        raise ModelError(f"{source}: bodies {missing[:5]} of robot {robot.name!r} are not bodies of the file")
    ids = [names[b] for b in robot.names]
    if model.nv != robot.dof or any(int(model.body_jntnum[i]) != 1 for i in ids):
        raise ModelError(f"{source}: robot {robot.name!r} does not match the file's joints (was it read from "
                         f"another file?)")
    return ids


def _body_frame_inertias(mj, model, robot: Robot, params, convention: str, ids: list[int]) -> np.ndarray:
    """Pseudo-inertias ``(n, 4, 4)`` of the robot's bodies in their MuJoCo body frames."""
    from ..pga import inverse_transform

    p = np.asarray(params, dtype=float)
    if p.size != 10 * robot.n:
        raise ModelError(f"expected {10 * robot.n} parameters (10 per body of {robot.name!r}), got {p.size}")
    n = I.from_convention(p.reshape(robot.n, 10), convention)
    if convention != "paper":  # link frames -> the world frame at q = 0
        n = I.transform(n, robot.M0)
    data = mj.MjData(model)
    data.qpos[:] = model.qpos0
    mj.mj_kinematics(model, data)
    out = np.empty_like(n)
    for k, i in enumerate(ids):
        t = np.eye(4)
        t[:3, :3], t[:3, 3] = data.xmat[i].reshape(3, 3), data.xpos[i]
        out[k] = I.transform(n[k], inverse_transform(t))
    return out


def _principal(n: np.ndarray, what: str) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """``(mass, centre of mass (3,), quat (4,), principal moments (3,))`` of a pseudo-inertia in the body frame.

    Refused: not finite, mass <= 0, a negative principal moment beyond rounding (1e-9 of the largest entry of ``n``).
    """
    if not np.all(np.isfinite(n)):
        raise ModelError(f"{what}: cannot write a pseudo-inertia with NaN or inf")
    m, h, j_o = I.split(n)
    m = float(m)
    if not m > 0:
        raise ModelError(f"{what}: mass {m:.6g} <= 0: a moving MuJoCo body needs a positive mass (<inertial "
                         f"mass>); not representable")
    c = h / m
    j_c = j_o - m * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
    d, r = np.linalg.eigh(0.5 * (j_c + j_c.T))
    if d[0] < -1e-9 * max(float(np.abs(n).max()), np.finfo(float).tiny):  # beyond rounding of the body's scale
        raise ModelError(f"{what}: principal moment of inertia {d[0]:.6g} < 0 about the centre of mass: not "
                         f"physically consistent, no MJCF <inertial diaginertia>; not representable")
    if np.linalg.det(r) < 0:
        r[:, 0] = -r[:, 0]
    quat = np.zeros(4)
    import mujoco as mj

    mj.mju_mat2Quat(quat, r.ravel())
    return m, c, quat, np.maximum(d, 0.0)


def _set_inertial(body, n: np.ndarray, what: str) -> None:
    """Set a spec body's explicit inertial (principal axes and moments) to pseudo-inertia ``n`` (body frame)."""
    m, c, quat, d = _principal(n, what)
    body.explicitinertial = True
    body.mass, body.ipos, body.iquat, body.inertia = m, c, quat, d
    body.fullinertia = [np.nan, 0, 0, 0, 0, 0]  # undefined: diaginertia and quat are used


def _zero_welded(by_id: dict, moving: set[int]) -> list[str]:
    """Zero the inertia of bodies welded to a moving body (its identified values hold the whole group)."""
    zeroed = []
    for body in by_id.values():
        if body.id in moving or body.id <= 0 or len(body.joints):
            continue
        up = body.parent
        while up is not None and up.id > 0 and not len(up.joints):
            up = up.parent
        if up is not None and up.id > 0:  # welded to a moving body, not to the world
            body.explicitinertial = True
            body.mass, body.ipos, body.iquat, body.inertia = 0.0, [0, 0, 0], [1, 0, 0, 0], [0, 0, 0]
            body.fullinertia = [np.nan, 0, 0, 0, 0, 0]
            zeroed.append(body.name or f"body{body.id}")
    if not zeroed:
        return []
    return [f"--mjcf: bodies welded to a moving body ({', '.join(zeroed[:5])}{', ...' if len(zeroed) > 5 else ''}) "
            f"written with zero mass: the moving body's identified inertia holds the whole rigid group"]


def _compiler_options(mj, spec) -> list[str]:
    """Compiler options that would change the written inertias, set so that they are used as written."""
    c = spec.compiler
    changed = []
    if c.inertiafromgeom == mj.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE:
        c.inertiafromgeom = mj.mjtInertiaFromGeom.mjINERTIAFROMGEOM_AUTO
        changed.append('inertiafromgeom="auto" (was "true", which would recompute them from the geoms)')
    for attr, off, what in (("boundmass", 0.0, "a lower bound on masses"),
                            ("boundinertia", 0.0, "a lower bound on moments"),
                            ("settotalmass", -1.0, "a rescaling of every mass")):
        if getattr(c, attr) != off:
            changed.append(f"{attr}=\"{off:g}\" (was {getattr(c, attr):g}: {what})")
            setattr(c, attr, off)
    if c.balanceinertia:
        c.balanceinertia = False
        changed.append('balanceinertia="false" (was "true": it alters inertias)')
    return [f"--mjcf: <compiler {x}>" for x in changed]


def _set_joints(by_id: dict, robot: Robot, ids: list[int], drives: dict, source: Path) -> list[str]:
    """Each moving body's joint: ``armature``, ``damping``, ``frictionloss`` from the drive terms; the notes."""
    set_, cleared, offsets = {}, {}, []
    for i, jname in enumerate(robot.joint_names):
        joint = by_id[ids[i]].joints[0]
        terms = drives.get(jname) or {}
        for kind, (attr, what) in _JOINT_ATTRS.items():
            v = terms.get(kind)
            if v is not None and not v >= 0:
                raise ModelError(f"{source}: joint {jname!r}: {what} {kind} = {v:.6g} < 0 has no MJCF {attr}")
            old = np.ravel(getattr(joint, attr))
            if v is None and np.any(old != 0):
                cleared.setdefault(attr, []).append(jname)
            elif v is not None:
                set_.setdefault(attr, []).append(jname)
            _set_attr(joint, attr, 0.0 if v is None else float(v))
        if terms.get("Fo") is not None:
            offsets.append(f"{jname} {terms['Fo']:.6g}")
    notes = []
    if set_:
        notes.append("--mjcf: " + "; ".join(f"{attr} of {len(j)} joint{'s' * (len(j) > 1)}" for attr, j in set_.items())
                     + " set to the identified values")
    if cleared:
        notes.append("--mjcf: " + "; ".join(f"{attr} of {', '.join(j)}" for attr, j in cleared.items())
                     + " set to 0 (nonzero in the source; the identified model has no such term: --rotor, --friction "
                       "estimate it)")
    if offsets:
        notes.append("--mjcf: MJCF has no joint torque offset: Fo left out (" + ", ".join(offsets) + ")")
    return notes


def _set_attr(joint, attr: str, value: float) -> None:
    """Set a joint attribute held as a scalar or as coefficients (MuJoCo 4's ``damping``: linear, then higher orders).

    A vector gets ``[value, 0, ...]``: the identified friction is linear.
    """
    old = getattr(joint, attr)
    if np.ndim(old):
        vec = np.zeros(np.shape(old))
        vec[0] = value
        setattr(joint, attr, vec)
    else:
        setattr(joint, attr, value)


def _to_xml(spec, dest: Path) -> str:
    """MuJoCo's XML of the edited spec (compiled first: a body MuJoCo refuses is a one-line error)."""
    try:
        spec.compile()
        return spec.to_xml()
    except Exception as exc:  # noqa: BLE001 - MuJoCo raises ValueError and others
        raise ModelError(f"{dest}: MuJoCo refuses the identified model ({one_line(exc)}); not written") from None


def _relocate_assets(text: str, spec, source: Path, dest: Path) -> str:
    """Point ``meshdir``/``texturedir`` at the source's asset folders when ``dest`` is in another folder."""
    if source.resolve().parent == dest.resolve().parent:
        return text
    files = [a.file for a in (*spec.meshes, *spec.textures, *spec.hfields, *spec.skins) if getattr(a, "file", "")]
    if not files:
        return text
    root = xmledit.parse(text, str(dest))
    compiler = root.find("compiler")
    if compiler is None:  # pragma: no cover - MuJoCo's writer always writes one
        return text
    edit = xmledit.Editor(text)
    values = {}
    for attr in ("meshdir", "texturedir"):
        old = getattr(spec.compiler, attr, "") or ""
        if not os.path.isabs(old):
            values[attr] = os.path.relpath(source.resolve().parent / old, dest.resolve().parent)
    edit.set(compiler, **values)
    return edit.text()


def _random_states(robot: Robot, count: int = 64, seed: int = 0) -> tuple[np.ndarray, ...]:
    """``(q, dq, ddq)``, each ``(count, dof)``: positions within ±1 (rad or m), rates standard normal."""
    rng = np.random.default_rng(seed)
    return (rng.uniform(-1.0, 1.0, (count, robot.dof)), rng.normal(size=(count, robot.dof)),
            rng.normal(size=(count, robot.dof)))


def _drive_vectors(robot: Robot, drives: dict) -> dict[str, np.ndarray]:
    """``{kind: (dof,)}``: each coordinate's drive term of each kind (0 when not identified)."""
    return {k: np.array([float((drives.get(j) or {}).get(k) or 0.0) for j in robot.joint_names])
            for k in ("Ia", "Fv", "Fc", "Fo")}


def _rotate_base(mj, spec, rot: np.ndarray) -> list[str]:
    """Rotate every body on the world body by ``rot`` about the world's origin."""
    quat = np.zeros(4)
    mj.mju_mat2Quat(quat, rot.reshape(-1))
    names = []
    for body in spec.worldbody.bodies:
        old = np.asarray(body.quat, dtype=float)
        new = np.zeros(4)
        mj.mju_mulQuat(new, quat, old / np.linalg.norm(old))
        body.pos = rot @ np.asarray(body.pos, dtype=float)
        body.quat = new
        names.append(repr(body.name))
    angle = float(np.degrees(np.arccos(np.clip((np.trace(rot) - 1) / 2, -1.0, 1.0))))
    return [f"--mjcf: the mounting tilt ({angle:.3g} degree) written as the orientation of the bodies on the world "
            f"body ({', '.join(names)})"]


def _check(path: Path, dest: Path, robot: Robot, values: tuple, states, expected, tolerance: float,
           check_robot: Robot | None = None) -> list[str]:
    """Reload the written file; its ``mj_inverse`` against ``expected`` or the parameters' own forces (module doc).

    ``values`` is ``(params, convention, drives)`` as :func:`write_mjcf` takes them; ``check_robot``
    the robot whose gravity the written file has (a mounting tilt), for the parameters' own forces.
    """
    from ..regressor.tp import regressor

    q, dq, ddq = (np.asarray(x, dtype=float) for x in (states if states is not None else _random_states(robot)))
    if q.ndim != 2 or q.shape[1] != robot.dof or not q.shape == dq.shape == ddq.shape:
        raise BaseparamsError(f"--mjcf: states must be three (S, {robot.dof}) arrays, got {q.shape}, {dq.shape}, "
                              f"{ddq.shape}")
    params, convention, drives = values
    pi = np.asarray(params, dtype=float).ravel() if convention == "paper" else _to_paper(robot, params, convention)
    d = _drive_vectors(robot, drives)
    want = regressor(check_robot or robot, q, dq, ddq) @ pi + d["Ia"] * ddq + d["Fv"] * dq
    source = "parameters' own"
    if expected is not None:
        want, source = np.asarray(expected, dtype=float), "identification's own predicted"
        if want.shape != q.shape:
            raise BaseparamsError(f"--mjcf: expected forces of shape {q.shape}, got {want.shape}")
    try:
        got = mjcf_inverse(path, robot, q, dq, ddq, frictionloss=False, what=f"{dest} (as written)")
    except ModelError as exc:
        raise ModelError(f"{exc}; not written") from None
    scale = float(np.sqrt(np.mean(want**2))) or 1.0
    err = float(np.sqrt(np.mean((got - want) ** 2))) / scale
    if not err <= tolerance:
        raise ModelError(f"{dest}: MuJoCo's inverse dynamics of the written model differs from the {source} "
                         f"rigid-body, armature and damping forces by {err:.3g} of their RMS (> {tolerance:g}) on "
                         f"{len(q)} states; not written")
    notes = [f"--mjcf: reloaded by MuJoCo: mj_inverse reproduces the {source} rigid-body, armature and damping "
             f"torques to {err:.2g} of their RMS on {len(q)} states (tolerance {tolerance:g})"]
    if np.any(d["Fc"]):
        with_fc = want + d["Fc"] * np.sign(dq)
        got_fc = mjcf_inverse(path, robot, q, dq, ddq, frictionloss=True, what=str(dest))
        err_fc = float(np.sqrt(np.mean((got_fc - with_fc) ** 2))) / (float(np.sqrt(np.mean(with_fc**2))) or 1.0)
        notes.append(f"--mjcf: Coulomb friction written as frictionloss, a soft constraint bounded by Fc (not "
                     f"Fc sign(dq): smooth through zero velocity, acceleration-dependent there): with it, mj_inverse "
                     f"differs from the model with Fc sign(dq) by {err_fc:.2g} of its RMS on these states")
    return notes


def _to_paper(robot: Robot, params, convention: str) -> np.ndarray:
    """Link-frame parameters ``(10 n,)`` in ``convention`` -> ``paper`` (world frame at q = 0)."""
    n = I.transform(I.from_convention(np.asarray(params, dtype=float).reshape(robot.n, 10), convention), robot.M0)
    return I.to_convention(n, "paper").ravel()


def mjcf_inverse(path: str | Path, robot: Robot, q, dq, ddq, *, frictionloss: bool = True,
                 what: str | None = None) -> np.ndarray:
    """MuJoCo's inverse dynamics (``mj_inverse``) of an MJCF file at states of ``robot``.

    Contacts, joint limits, equalities and springs are disabled (they are not part of an
    identified model); dry friction (``frictionloss``) as asked.

    Parameters
    ----------
    path : str or Path
        The MJCF file (e.g. written by :func:`write_mjcf`).
    robot : Robot
        The robot read from it (or from its source): ``robot.dof`` hinge and slide joints in
        MuJoCo's dof order.
    q, dq, ddq : array_like, shape ``(S, robot.dof)``
        Positions (from ``qpos0``), velocities and accelerations.
    frictionloss : bool
        Keep MuJoCo's dry-friction constraints (default) or disable them.
    what : str, optional
        The name used in messages (default ``path``).

    Returns
    -------
    ndarray, shape ``(S, robot.dof)``
        ``qfrc_inverse`` [N m or N], columns the robot's coordinates.

    Raises
    ------
    ModelError
        A file MuJoCo rejects, or one whose joints are not the robot's.
    """
    import mujoco as mj

    what = what or str(path)
    try:
        model = mj.MjModel.from_xml_path(str(path))
    except Exception as exc:  # noqa: BLE001
        raise ModelError(f"{what}: MuJoCo cannot load it ({one_line(exc)})") from None
    if model.nv != robot.dof or model.nq != robot.dof:
        raise ModelError(f"{what}: {model.nv} MuJoCo dofs, robot {robot.name!r} has {robot.dof}")
    dis = mj.mjtDisableBit
    model.opt.disableflags |= int(dis.mjDSBL_CONTACT) | int(dis.mjDSBL_LIMIT) | int(dis.mjDSBL_EQUALITY) | \
        int(dis.mjDSBL_SPRING) | (0 if frictionloss else int(dis.mjDSBL_FRICTIONLOSS))
    data = mj.MjData(model)
    q, dq, ddq = (np.atleast_2d(np.asarray(x, dtype=float)) for x in (q, dq, ddq))
    out = np.empty_like(q)
    for k in range(len(q)):
        data.qpos[:] = model.qpos0 + q[k]
        data.qvel[:], data.qacc[:] = dq[k], ddq[k]
        mj.mj_inverse(model, data)
        out[k] = data.qfrc_inverse
    return out


def check_mjcf_request(model, method: str, dest, what: str = "mjcf=") -> None:
    """Refuse, before any fit, an MJCF export that cannot be honoured (the CLI's and ``bp.identify``'s check).

    Parameters
    ----------
    model : object
        The model as given: it must be an MJCF (``.xml``) or URDF (``.urdf``) file.
    method : str
        The identification method: it must be ``physical`` (full, physically consistent bodies).
    dest : str or Path
        The file to write: it must end in ``.xml``.
    what : str
        The option's name in messages (its keyword, ``mjcf=``; the command line names the flag).

    Raises
    ------
    BaseparamsError
        Another method, a model that is not such a file, another suffix (each one line, saying
        nothing was fitted).
    """
    if method != "physical":
        raise BaseparamsError(f"{what} needs method=physical: least squares gives base parameters, not bodies "
                              f"(nothing was fitted)")
    path = Path(os.fspath(model)) if isinstance(model, (str, os.PathLike)) else None
    if path is None or path.suffix.lower() not in (".xml", ".urdf") or not path.is_file():
        shown = model if path is not None else type(model).__name__
        raise BaseparamsError(f"{what} writes the model file as MJCF with the identified values: it needs an MJCF "
                              f"(.xml) or URDF (.urdf) model file, got {shown} (nothing was fitted)")
    if Path(os.fspath(dest)).suffix.lower() != ".xml":
        raise BaseparamsError(f"{what} {dest}: an MJCF file must end in .xml (nothing was fitted)")
