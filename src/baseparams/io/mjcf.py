"""MJCF (MuJoCo XML) reader, through MuJoCo itself.

The file is parsed and compiled by the ``mujoco`` package (``MjSpec.from_file`` then
``compile``), and the robot is read off the compiled ``MjModel`` and its kinematics at
``qpos0`` (our q = 0). Whatever MuJoCo accepts
(``<include>``, default classes, ``<frame>``, unnamed bodies, several joints per body, ...) is
read as MuJoCo reads it; what it rejects is one line ``path: <MuJoCo's message>``.

Mapping:

* bodies with joints are moving links; a body without joints is welded to its parent (its
  inertia merged), or static when on the world (``floating``: a top-level body without a joint
  gets a floating joint). Unnamed bodies are ``body<id>``, unnamed joints ``<body>_joint<k>``;
* one hinge R, one slide P, one ball S, free F; two hinges through one point with perpendicular
  axes U; any other set of hinges and slides in one body is one compound joint C (its screws in
  MuJoCo's order, a product of exponentials in the body frame). The link frame is the body
  frame moved to the first joint's anchor (as Pinocchio loads MJCF inertias);
* inertias: ``body_mass, body_ipos, body_iquat, body_inertia``; ``dof_armature`` ->
  :attr:`Robot.armature` (free joints reordered to our ``(omega, v)``);
* equalities: ``connect`` (body or site form) -> spherical loop joint, ``weld`` -> fixed loop
  joint (``relpose``/``torquescale`` ignored, with a note when not the default), ``joint`` with
  its ``polycoef`` (a polynomial of degree up to 4, from ``qpos0``) and fixed-tendon equalities
  that couple 1-dof joints linearly -> couplings; inactive equalities are skipped with a note.
  A weld or connect to a mocap body (a control device the simulation moves) is left out with a
  note, unless ``mocap_welds='keep'`` (:class:`~baseparams.enums.MocapWelds`).
  Actuated joints are preferred as the independent coordinates of closed loops.

Missing mesh (texture, height field, skin) files: those assets and the geoms using them are
stripped and the model compiled again; a moving body whose inertia came from a stripped geom is
named in a note (its values are placeholders; the base-parameter structure does not depend on
them). ``mujoco`` is imported only here, when an MJCF file is read.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ..enums import MocapWelds
from ..errors import ModelError
from ..files import MODEL_MAX_BYTES, check_input
from ..kinematics.loops import choose_independent
from ..model.bounds import check_magnitude
from ..model.builder import RobotBuilder, quat_pose
from ..model.inertia import Inertia, check_inertia
from ..model.robot import Coupling, Robot, compound_screw


class MJCFWarning(UserWarning):
    """Something in an MJCF file read with a caveat (stripped assets, ignored weld options...)."""


def _one_line(exc: BaseException) -> str:
    """MuJoCo's whole message on one line (its reason is often on the second: ``XML parse error 18:``)."""
    text = str(exc).strip() or type(exc).__name__
    out = ""
    for line in (x.strip() for x in text.splitlines()):
        if line:
            out += ("" if not out else " " if out.endswith(":") else "; ") + line
    return out


def _import_mujoco():
    try:
        import mujoco
    except ImportError as exc:  # pragma: no cover - a core dependency
        raise ModelError(f"reading MJCF needs the 'mujoco' package ({exc})") from None
    return mujoco


_ASSET_ERROR = re.compile(r"(opening file|could not open|resource not found|file not found|no such file|"
                          r"error reading|cannot read|decoder|png|stl|obj|msh)", re.IGNORECASE)


def _resolve(base: Path, subdir: str, file: str) -> bool:
    f = Path(file)
    if f.is_absolute():
        return f.exists()
    return any(p.exists() for p in (base / subdir / f, base / f, base / subdir / f.name))


def _strip_assets(mj, spec, base: Path, everything: bool) -> dict[str, str]:
    """Delete file-backed meshes, textures, height fields and skins whose file is missing.

    All of them with ``everything``, and the geoms using them; returns ``{body name: geom kind}``
    for the bodies that lost a geom.
    """
    meshdir = spec.compiler.meshdir or spec.meshdir or ""
    texdir = spec.compiler.texturedir or spec.texturedir or ""
    gone_mesh, gone_hf, gone_tex = set(), set(), set()
    for mesh in list(spec.meshes):
        if mesh.file and (everything or not _resolve(base, meshdir, mesh.file)):
            gone_mesh.add(mesh.name)
            spec.delete(mesh)
    for hf in list(spec.hfields):
        if hf.file and (everything or not _resolve(base, "", hf.file)):
            gone_hf.add(hf.name)
            spec.delete(hf)
    for tex in list(spec.textures):
        files = [tex.file] + [f for f in getattr(tex, "cubefiles", []) if f]
        if any(files) and (everything or not all(_resolve(base, texdir, f) for f in files if f)):
            gone_tex.add(tex.name)
            spec.delete(tex)
    for skin in list(spec.skins):
        if skin.file and (everything or not _resolve(base, meshdir, skin.file)):
            spec.delete(skin)
    for mat in spec.materials:
        tex = list(mat.textures)
        if any(t in gone_tex for t in tex):
            mat.textures = ["" if t in gone_tex else t for t in tex]
    lost: dict[str, str] = {}
    for geom in list(spec.geoms):
        if (geom.type == mj.mjtGeom.mjGEOM_MESH and geom.meshname in gone_mesh) or \
                (geom.type == mj.mjtGeom.mjGEOM_HFIELD and geom.hfieldname in gone_hf):
            lost[geom.parent.name] = "mesh" if geom.type == mj.mjtGeom.mjGEOM_MESH else "height field"
            spec.delete(geom)
    return lost


def _parsed(mj, path: Path, edit):
    """The file parsed into an ``MjSpec``, ``edit`` (if any) called on it."""
    spec = mj.MjSpec.from_file(str(path))
    if edit is not None:
        edit(spec)
    return spec


def _compile(mj, path: Path, edit=None):
    """``(model, notes, affected bodies, spec)``: parse and compile, stripping missing asset files if needed.

    The files the model reads and the numbers MuJoCo allocates from are checked first
    (:func:`baseparams.io.sources.mjcf_sources`). ``edit``: called with each parsed spec before
    it is compiled.
    """
    from .sources import mjcf_sources

    mjcf_sources(path)
    try:
        spec = _parsed(mj, path, edit)
    except Exception as exc:  # noqa: BLE001 - MuJoCo raises ValueError and others
        raise ModelError(f"{path}: {_one_line(exc)}") from None
    try:
        return spec.compile(), [], set(), spec
    except Exception as exc:  # noqa: BLE001
        first = exc
    if not _ASSET_ERROR.search(str(first)):
        raise ModelError(f"{path}: {_one_line(first)}")
    base = path.parent
    spec = _parsed(mj, path, edit)
    lost = _strip_assets(mj, spec, base, everything=False)
    explicit = {b for b in lost if spec.body(b).explicitinertial}  # before compiling: fusestatic removes bodies
    try:
        model = spec.compile()
    except Exception:  # noqa: BLE001 - the missing file was not found by our resolution: strip all
        spec = _parsed(mj, path, edit)
        lost = _strip_assets(mj, spec, base, everything=True)
        explicit = {b for b in lost if spec.body(b).explicitinertial}
        model = None
    notes: list[str] = []
    placeholders: list[str] = []
    for _ in range(len(spec.bodies) + 1):
        if model is not None:
            break
        try:
            model = spec.compile()
        except Exception as exc:  # noqa: BLE001
            msg = str(exc)
            hit = re.search(r"mass and inertia of moving bodies.*?Element name '([^']*)'", msg, re.DOTALL)
            body = spec.body(hit.group(1)) if hit and hit.group(1) else None
            if body is None or body.name not in lost or body.explicitinertial:
                raise ModelError(f"{path}: {_one_line(exc)} (after stripping missing asset files: "
                                 f"{_one_line(first)})") from None
            body.explicitinertial = True  # this body only: its inertia came from stripped geoms
            body.mass, body.ipos, body.iquat, body.inertia = 1e-3, [0, 0, 0], [1, 0, 0, 0], [1e-6] * 3
            placeholders.append(body.name)
    fromgeom = spec.compiler.inertiafromgeom
    always = fromgeom == mj.mjtInertiaFromGeom.mjINERTIAFROMGEOM_TRUE
    never = fromgeom == mj.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    # a body fused into its parent by the compiler (fusestatic; MuJoCo's URDF import) is looked up by the
    # name it had before compiling
    affected = sorted(b for b in lost if not never and (always or b not in explicit or b in placeholders))
    notes.append(f"{path}: missing asset files ({_one_line(first)}): stripped them and the geoms using them")
    for b in affected:
        what = "a placeholder inertia (mass 1e-3)" if b in placeholders else "the remaining geoms"
        notes.append(f"{path}: body {b!r}: its inertia came from stripped geoms; {what} used instead "
                     f"(placeholder values; the base-parameter structure does not depend on them)")
    return model, notes, set(affected), spec


def compiled_spec(path: str | Path):
    """The file's ``MjSpec`` and ``MjModel``, as :func:`load_mjcf` reads them.

    Parameters
    ----------
    path : str or Path
        The MJCF file.

    Returns
    -------
    spec : mujoco.MjSpec
        The parsed file, compiled (missing mesh, texture, height-field and skin files stripped
        with the geoms using them; static bodies fused when the file asks ``fusestatic``); its
        bodies' ``id`` are the model's body indices.
    model : mujoco.MjModel
        The compiled model.
    notes : list of str
        What was stripped, one line each.

    Raises
    ------
    ModelError
        A missing file or anything MuJoCo rejects (``path: <MuJoCo's message>``).
    """
    path = check_input(path, MODEL_MAX_BYTES, error=ModelError)
    model, notes, _, spec = _compile(_import_mujoco(), path)
    return spec, model, notes


def one_line(exc: BaseException) -> str:
    """MuJoCo's message on one line (its reason is often on a second line).

    Parameters
    ----------
    exc : BaseException
        What MuJoCo raised.

    Returns
    -------
    str
        The message's lines joined.
    """
    return _one_line(exc)


def _pose(pos, rot) -> np.ndarray:
    t = np.eye(4)
    t[:3, :3] = np.asarray(rot, dtype=float).reshape(3, 3)
    t[:3, 3] = pos
    return t


def load_mjcf(path: str | Path, name: str | None = None, gravity=None, floating: bool = False,
              strict_inertia: bool = False, mocap_welds: str = "drop", edit=None) -> Robot:
    """Read an MJCF file into a :class:`Robot` (see the module doc).

    Parameters
    ----------
    path : str or Path
        The MJCF file (parsed and compiled by MuJoCo).
    name : str, optional
        The robot's name; default the model's name (unless MuJoCo's default ``MuJoCo Model``),
        else the file's stem.
    gravity : array_like, shape ``(3,)``, optional
        Gravity in the world frame, m/s^2; default the model's ``opt.gravity`` (zero, with a
        warning, when the model disables gravity).
    floating : bool, optional
        A top-level body without a joint gets a floating (F) joint.
    strict_inertia : bool, optional
        Physically infeasible inertias of moving bodies are errors (warnings otherwise).
    mocap_welds : {'drop', 'keep'}, optional
        The ``weld`` and ``connect`` equalities to a mocap body (a control device the simulation
        moves: Meta-World's and Fetch's hands are welded to one, for actuation): ``drop``
        (default) leaves them out, with a note; ``keep`` reads them as loop joints to the world
        whose world side may be placed anywhere
        (:attr:`~baseparams.model.robot.LoopJoint.anchor_free`), also noted
        (:class:`~baseparams.enums.MocapWelds`).
    edit : callable, optional
        Called with the parsed ``MjSpec`` before it is compiled (it may change values:
        :mod:`baseparams.io.snapfile` sets rounded right angles exact).

    Returns
    -------
    Robot
        The robot at ``qpos0`` (our q = 0), with ``armature``, couplings and loop joints from
        the equalities; with loops, its independent coordinates are chosen from the constraints
        (:func:`~baseparams.kinematics.loops.choose_independent`, actuated joints preferred).

    Raises
    ------
    ModelError
        A missing file, anything MuJoCo rejects (``path: <MuJoCo's message>``) or an unsupported
        construct.

    Warns
    -----
    MJCFWarning
        Stripped assets, ignored weld options, inactive or void equalities, disabled gravity.
    InertiaWarning
        Physically infeasible inertias of moving bodies (without ``strict_inertia``).
    """
    path = check_input(path, MODEL_MAX_BYTES, error=ModelError)
    mj = _import_mujoco()
    out = _compile(mj, path, edit)
    model, notes = out[0], out[1]
    for note in notes:
        warnings.warn(note, MJCFWarning, stacklevel=2)
    _check_model(model, path)
    data = mj.MjData(model)
    data.qpos[:] = model.qpos0
    mj.mj_kinematics(model, data)
    return _robot(mj, model, data, path, name, gravity, floating, strict_inertia, MocapWelds(mocap_welds))


def _check_model(model, path: Path) -> None:
    """Refuse names that are not UTF-8 and absurd numbers (:mod:`baseparams.model.bounds`), naming the element."""
    for raw in bytes(model.names).split(b"\0"):
        try:
            raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise ModelError(f"{path}: the name '{raw.decode('utf-8', 'backslashreplace')}' is not UTF-8 text "
                             f"(byte 0x{raw[exc.start]:02x}); names must be UTF-8") from None
    checks = [("body", "pos", model.body_pos, "length"), ("body", "inertial pos", model.body_ipos, "length"),
              ("body", "mass", model.body_mass, "mass"), ("body", "inertia", model.body_inertia, "inertia"),
              ("jnt", "pos", model.jnt_pos, "length")]
    for kind, attr, values, bound in checks:
        for i in range(1 if kind == "body" else 0, len(values)):  # body 0: the world
            label = "body" if kind == "body" else "joint"
            check_magnitude(values[i], bound, f"{path}: <{label} name={_name(model, kind, i, f'{label}{i}')!r}> {attr}")
    for i in range(model.njnt):
        if not np.all(np.isfinite(model.jnt_axis[i])) or np.linalg.norm(model.jnt_axis[i]) < 0.5:
            name = _name(model, "jnt", i, f"joint{i}")
            raise ModelError(f"{path}: <joint name={name!r}> axis: zero or not finite after normalisation "
                             "(components beyond 1e154?)")


def _name(model, kind, i: int, fallback: str) -> str:
    return model.names[getattr(model, f"name_{kind}adr")[i]:].split(b"\0", 1)[0].decode() or fallback


def _joint_kind(mj, model, data, joints: list[int], bname: str, what: str):
    """``(type, axes, anchor (3,) world)`` of a body's joints (MuJoCo order)."""
    jt = model.jnt_type
    rot = data.xmat[model.jnt_bodyid[joints[0]]].reshape(3, 3)
    anchor = data.xanchor[joints[0]].copy()
    types = [int(jt[j]) for j in joints]
    free, ball = int(mj.mjtJoint.mjJNT_FREE), int(mj.mjtJoint.mjJNT_BALL)
    slide, hinge = int(mj.mjtJoint.mjJNT_SLIDE), int(mj.mjtJoint.mjJNT_HINGE)
    axes = [rot.T @ data.xaxis[j] for j in joints]
    axes = [a / np.linalg.norm(a) for a in axes]
    if len(joints) == 1:
        t = types[0]
        if t == free:
            return "F", None, anchor
        if t == ball:
            return "S", None, anchor
        return ("R" if t == hinge else "P"), axes[0], anchor
    if free in types or ball in types:
        raise ModelError(f"{what}: a {'free' if free in types else 'ball'} joint together with other joints "
                         f"in one body is not supported")
    pts = [rot.T @ (data.xanchor[j] - anchor) for j in joints]
    if (len(joints) == 2 and types == [hinge, hinge] and np.linalg.norm(pts[1]) < 1e-12
            and abs(axes[0] @ axes[1]) < 1e-12):
        return "U", np.stack(axes), anchor
    rows = [compound_screw(a, slide=True) if t == slide else compound_screw(a, point=p)
            for t, a, p in zip(types, axes, pts)]
    return "C", np.array(rows), anchor


@dataclass
class _Walk:
    """Bookkeeping of the walk over MuJoCo's bodies, shared with :func:`_equalities`."""

    link_of: list[str | None]  # the moving link carrying each body (None: the world)
    t_link: dict[str | None, np.ndarray] = field(default_factory=lambda: {None: np.eye(4)})  # link frames at q = 0
    dof_map: dict[int, int] = field(default_factory=dict)  # MuJoCo dof -> our coordinate
    armature: list[float] = field(default_factory=list)
    joint_names: dict[int, str] = field(default_factory=dict)


def _robot(mj, model, data, path: Path, name, gravity, floating: bool, strict_inertia: bool,
           mocap_welds: MocapWelds = MocapWelds.DROP) -> Robot:
    gravity = _gravity(mj, model, path, gravity)
    mname = model.names.split(b"\0", 1)[0].decode()
    b = RobotBuilder(name or (mname if mname and mname != "MuJoCo Model" else path.stem), gravity=gravity)
    bnames = ["world"] + [_name(model, "body", i, f"body{i}") for i in range(1, model.nbody)]
    w = _Walk(link_of=[None] * model.nbody)
    for i in range(1, model.nbody):
        _add_body(mj, model, data, path, b, w, i, bnames[i], floating, strict_inertia)
    couplings = _equalities(mj, model, data, path, b, bnames, w.link_of, w.t_link, w.joint_names, w.dof_map,
                            mocap_welds)
    robot = b.build()
    robot = replace(robot, armature=np.array(w.armature))
    if couplings:
        robot = replace(robot, couplings=tuple(couplings))
    robot = _with_limits(mj, model, robot, w.dof_map)
    if robot.has_loops:  # MJCF does not say which coordinates are independent: prefer actuated joints
        robot = choose_independent(robot, _preferred_coordinates(mj, model, robot, w.dof_map))
    return robot


def _with_limits(mj, model, robot: Robot, dof_map: dict[int, int]) -> Robot:
    """The robot with :attr:`Robot.limits` of its hinge and slide joints.

    Positions: ``range`` of limited joints, relative to ``qpos0`` (our q = 0); efforts: the smallest
    of the joint's ``actuatorfrcrange`` and the force ranges times the gear of the force-limited
    actuators with a joint transmission on it; velocities: NaN (MJCF has none). Nothing known and
    no hinge without ``range``: ``limits`` stays None (an unlimited hinge's NaN position limits say it
    has none: any number of turns).
    """
    out = np.full((robot.dof, 4), np.nan)
    hinge, slide = int(mj.mjtJoint.mjJNT_HINGE), int(mj.mjtJoint.mjJNT_SLIDE)
    coord = {}
    unlimited = False  # a hinge without range: declared without position limits (any number of turns)
    for j in range(model.njnt):
        d = int(model.jnt_dofadr[j])
        if int(model.jnt_type[j]) in (hinge, slide) and d in dof_map:
            coord[j] = k = dof_map[d]
            unlimited |= int(model.jnt_type[j]) == hinge and not model.jnt_limited[j]
            if model.jnt_limited[j]:
                out[k, :2] = np.asarray(model.jnt_range[j], dtype=float) - model.qpos0[model.jnt_qposadr[j]]
            if getattr(model, "jnt_actfrclimited", np.zeros(model.njnt))[j]:
                out[k, 3] = float(np.abs(model.jnt_actfrcrange[j]).max())
    joint_trn = (int(mj.mjtTrn.mjTRN_JOINT), int(mj.mjtTrn.mjTRN_JOINTINPARENT))
    for a in range(model.nu):
        j = int(model.actuator_trnid[a, 0])
        if int(model.actuator_trntype[a]) in joint_trn and j in coord and model.actuator_forcelimited[a]:
            eff = float(np.abs(model.actuator_forcerange[a]).max() * abs(model.actuator_gear[a, 0]))
            out[coord[j], 3] = np.fmin(out[coord[j], 3], eff)
    out[:, 3] = np.where(out[:, 3] > 0, out[:, 3], np.nan)
    return replace(robot, limits=out) if np.isfinite(out).any() or unlimited else robot


def _gravity(mj, model, path: Path, gravity) -> np.ndarray:
    """``gravity`` if given, else the model's (zero, with a note, when the model disables it)."""
    if gravity is None:
        gravity = np.array(model.opt.gravity, dtype=float)
        if model.opt.disableflags & int(mj.mjtDisableBit.mjDSBL_GRAVITY) and np.any(gravity):
            warnings.warn(f"{path}: gravity is disabled (<flag gravity=\"disable\">): analysed with zero gravity",
                          MJCFWarning, stacklevel=4)
            gravity = np.zeros(3)
    return gravity


def _add_body(mj, model, data, path: Path, b: RobotBuilder, w: _Walk, i: int, bname: str, floating: bool,
              strict_inertia: bool) -> None:
    """Add MuJoCo body ``i`` to the builder.

    Merged into its parent when it has no joint (floating instead when ``floating`` and
    top-level), else a moving link with its joint, armature and dofs mapped.
    """
    what = f"{path}: body {bname!r}"
    p = int(model.body_parentid[i])
    plink = w.link_of[p]
    t_body = _pose(data.xpos[i], data.xmat[i])
    t_in = t_body @ quat_pose(model.body_ipos[i], model.body_iquat[i])
    mass, diag = float(model.body_mass[i]), np.array(model.body_inertia[i], dtype=float)
    j0, nj = int(model.body_jntadr[i]), int(model.body_jntnum[i])
    joints = list(range(j0, j0 + nj)) if nj > 0 else []
    for k, j in enumerate(joints):
        w.joint_names[j] = _name(model, "jnt", j, f"{bname}_joint{k}")
    if not joints:
        if floating and p == 0:
            jt, axis, t_l = "F", None, t_body
        else:
            b.add_link(bname, parent=plink, joint="fixed", origin=np.linalg.inv(w.t_link[plink]) @ t_body,
                       inertia=Inertia(mass, inertia=diag, frame=np.linalg.inv(t_body) @ t_in))
            w.link_of[i] = plink
            return
    else:
        jt, axis, anchor = _joint_kind(mj, model, data, joints, bname, what)
        t_l = _pose(anchor, data.xmat[i])
        if jt == "F" and p != 0:
            raise ModelError(f"{what}: a free joint is only supported on a top-level body")
    check_inertia(mass, np.diag(diag), f"{what}: inertia", strict=strict_inertia)
    jname = w.joint_names[joints[0]] if len(joints) == 1 else (
        "+".join(w.joint_names[j] for j in joints) if joints else f"{bname}_joint")
    _map_dofs(model, w, jt, joints)
    b.add_link(bname, parent=plink, joint=jt, origin=np.linalg.inv(w.t_link[plink]) @ t_l,
               axis=(0, 0, 1) if axis is None else (axis if jt != "U" else axis[0]),
               axis2=None if jt != "U" else axis[1],
               inertia=Inertia(mass, inertia=diag, frame=np.linalg.inv(t_l) @ t_in),
               joint_name=jname, actuated=True)  # all independent until loops choose
    w.link_of[i] = bname
    w.t_link[bname] = t_l


def _joint_ndof(model, j: int) -> int:
    """Dofs of MuJoCo joint ``j``: free 6, ball 3, hinge and slide 1."""
    return 6 if model.jnt_type[j] == 0 else 3 if model.jnt_type[j] == 1 else 1


def _map_dofs(model, w: _Walk, jt: str, joints: list[int]) -> None:
    """Append the armature of a new link's joint and map its MuJoCo dofs to our coordinates.

    The joint is ``jt`` made of MuJoCo ``joints`` (none: a floating joint of ours, zero armature).
    """
    arm = np.zeros(6) if not joints else np.concatenate(
        [model.dof_armature[model.jnt_dofadr[j]: model.jnt_dofadr[j] + _joint_ndof(model, j)] for j in joints])
    first = len(w.armature)
    if jt == "F" and joints:
        arm = np.r_[arm[3:], arm[:3]]  # MuJoCo free dofs (v, omega) -> ours (omega, v)
        d0 = int(model.jnt_dofadr[joints[0]])
        w.dof_map.update({d0 + k: first + (k + 3) % 6 for k in range(6)})
    else:
        d0 = int(model.jnt_dofadr[joints[0]]) if joints else -1
        for k in range(len(arm) if joints else 0):
            w.dof_map[d0 + k] = first + k
    w.armature.extend(arm.tolist())


def _preferred_coordinates(mj, model, robot: Robot, dof_map: dict[int, int]) -> set[int]:
    """Our coordinates of the joints driven by actuators (and the floating base's)."""
    prefer = set()
    for a in range(model.nu):
        if int(model.actuator_trntype[a]) in (int(mj.mjtTrn.mjTRN_JOINT), int(mj.mjtTrn.mjTRN_JOINTINPARENT)):
            j = int(model.actuator_trnid[a, 0])
            nd = _joint_ndof(model, j)
            adr = int(model.jnt_dofadr[j])
            prefer |= {dof_map[adr + k] for k in range(nd) if adr + k in dof_map}
    prefer |= set(range(6)) if robot.jtype[0] == "F" else set()
    return prefer


def _equalities(mj, model, data, path, b: RobotBuilder, bnames, link_of, t_link, joint_names, dof_map,
                mocap_welds: MocapWelds = MocapWelds.DROP) -> list:
    """Add loop joints for connect/weld; return the couplings (joint and fixed-tendon equalities)."""
    couplings: list[Coupling] = []
    eq = mj.mjtEq
    site = int(mj.mjtObj.mjOBJ_SITE)
    for e in range(model.neq):
        et = int(model.eq_type[e])
        kind = {int(eq.mjEQ_CONNECT): "connect", int(eq.mjEQ_WELD): "weld", int(eq.mjEQ_JOINT): "joint",
                int(eq.mjEQ_TENDON): "tendon"}.get(et, f"type {et}")
        ename = _name(model, "eq", e, f"{kind}{e}")
        what = f"{path}: <equality><{kind} name={ename!r}>"
        if not model.eq_active0[e]:
            warnings.warn(f"{what}: inactive (active=false): skipped", MJCFWarning, stacklevel=3)
            continue
        o1, o2 = int(model.eq_obj1id[e]), int(model.eq_obj2id[e])
        d = np.array(model.eq_data[e], dtype=float)
        if kind in ("connect", "weld"):
            b1, b2, w1, w2 = _loop_frames(model, data, e, kind, site, what)
            if kind == "weld" and abs(d[10] - 1.0) > 1e-12:
                warnings.warn(f"{what}: torquescale {d[10]:g} ignored (a weld is a fixed loop joint)",
                              MJCFWarning, stacklevel=3)
            l1, l2 = link_of[b1], link_of[b2]
            if l1 == l2:
                warnings.warn(f"{what}: both sides are on one rigid body: no constraint, skipped",
                              MJCFWarning, stacklevel=3)
                continue
            mocap = _mocap(model, bnames, b1, b2, what, mocap_welds)
            if mocap is None:
                continue
            i1 = -1 if l1 is None else b.body_index(l1)
            i2 = -1 if l2 is None else b.body_index(l2)
            (pl, pw), (cl, cw) = ((l1, w1), (l2, w2)) if i1 < i2 else ((l2, w2), (l1, w1))
            b.add_loop(ename, "S" if kind == "connect" else "fixed", parent=pl, child=cl,
                       origin=np.linalg.inv(t_link[pl]) @ pw, child_origin=np.linalg.inv(t_link[cl]) @ cw,
                       anchor_free=bool(mocap) and min(i1, i2) < 0)
        elif kind == "joint":
            if o2 < 0:
                raise ModelError(f"{what}: a joint locked by an equality is not supported (no joint2)")
            c1, c2 = _coord(model, o1, dof_map, what), _coord(model, o2, dof_map, what)
            poly = np.trim_zeros(d[2:5], "b")  # q1 = d0 + d1 q2 + d2 q2^2 + ... (from qpos0)
            couplings.append(Coupling(ename, c2, c1, float(d[1]), float(d[0]), poly=tuple(float(x) for x in poly)))
        elif kind == "tendon":
            couplings.append(_tendon_coupling(mj, model, o1, o2, d, dof_map, ename, what))
        else:
            raise ModelError(f"{what}: this equality type is not supported")
    return couplings


def _loop_frames(model, data, e: int, kind: str, site: int, what: str):
    """``(body1, body2, world frame on body1, on body2)`` of a connect or weld equality at qpos0."""
    o1, o2, d = int(model.eq_obj1id[e]), int(model.eq_obj2id[e]), np.array(model.eq_data[e], dtype=float)
    if int(model.eq_objtype[e]) == site:
        b1, b2 = int(model.site_bodyid[o1]), int(model.site_bodyid[o2])
        w1, w2 = (_pose(data.site_xpos[s], data.site_xmat[s]) for s in (o1, o2))
        if kind == "connect":
            w1[:3, :3] = w2[:3, :3] = np.eye(3)
        return b1, b2, w1, w2
    b1, b2 = o1, o2
    if kind == "connect":
        w1, w2 = np.eye(4), np.eye(4)
        w1[:3, 3] = data.xpos[b1] + data.xmat[b1].reshape(3, 3) @ d[0:3]
        w2[:3, 3] = data.xpos[b2] + data.xmat[b2].reshape(3, 3) @ d[3:6]
        return b1, b2, w1, w2
    t1, t2 = _pose(data.xpos[b1], data.xmat[b1]), _pose(data.xpos[b2], data.xmat[b2])
    rel = np.linalg.inv(t1) @ t2  # relpose: body2 in body1 at qpos0 (MuJoCo's default)
    given = quat_pose(d[3:6], d[6:10]) if np.linalg.norm(d[6:10]) > 1e-12 else rel
    if np.abs(given - rel).max() > 1e-6:
        warnings.warn(f"{what}: relpose differs from the qpos0 pose: ignored (the weld is read as a fixed loop joint "
                      f"at the file's pose)", MJCFWarning, stacklevel=4)
    return b1, b2, t2, t2


def _mocap(model, bnames, b1: int, b2: int, what: str, mode: MocapWelds) -> bool | None:
    """Whether a weld or connect ties a body to a mocap body (noted); None when it is left out (``drop``)."""
    mocap = [bnames[x] for x in (b1, b2) if int(model.body_mocapid[x]) >= 0]
    if not mocap:
        return False
    other = bnames[b2 if int(model.body_mocapid[b1]) >= 0 else b1]
    if mode == MocapWelds.DROP:
        warnings.warn(f"{what}: ties {other!r} to the mocap body {mocap[0]!r}, a control device the simulation moves "
                      f"(actuation): left out, {other!r} moves with its joints (mocap_welds='keep', "
                      f"--mocap-welds keep, "
                      f"keeps it as a loop joint to the world)", MJCFWarning, stacklevel=4)
        return None
    warnings.warn(f"{what}: ties {other!r} to the mocap body {mocap[0]!r}, a control device the simulation moves: kept "
                  f"as a loop joint to the world (mocap_welds='keep'), placed where {other!r} is at the reference",
                  MJCFWarning, stacklevel=4)
    return True


def _check_poly(d: np.ndarray, what: str) -> None:
    if np.any(d[2:5] != 0):
        raise ModelError(f"{what}: a tendon equality with a nonlinear polycoef {d[:5].tolist()} is not supported "
                         f"(a joint equality's is)")


def _coord(model, j: int, dof_map, what: str) -> int:
    if int(model.jnt_type[j]) not in (2, 3):
        raise ModelError(f"{what}: only hinge and slide joints can be coupled")
    return dof_map[int(model.jnt_dofadr[j])]


def _tendon_joints(mj, model, t: int, what: str) -> list[tuple[int, float]]:
    adr, num = int(model.tendon_adr[t]), int(model.tendon_num[t])
    out = []
    for w in range(adr, adr + num):
        if int(model.wrap_type[w]) != int(mj.mjtWrap.mjWRAP_JOINT):
            raise ModelError(f"{what}: only fixed tendons (linear joint combinations) are supported")
        out.append((int(model.wrap_objid[w]), float(model.wrap_prm[w])))
    return out


def _tendon_coupling(mj, model, t1: int, t2: int, d: np.ndarray, dof_map, ename: str, what: str) -> Coupling:
    """One linear coupling from a fixed-tendon equality ``L1 - L1(qpos0) = a0 + a1 (L2 - L2(qpos0))``.

    With fixed tendons ``L = sum c_j q_j``: one linear coupling of the 1-dof joints involved
    (any number of them, e.g. dm_control's quadruped ties pitch, knee and ankle). The coordinate
    with the largest coefficient is solved for: ``q_s = sum(-c_j / c_s q_j) + a0 / c_s``.
    """
    _check_poly(d, what)
    coef: dict[int, float] = {}
    for j, c in _tendon_joints(mj, model, t1, what):
        k = _coord(model, j, dof_map, what)
        coef[k] = coef.get(k, 0.0) + c
    if t2 >= 0:
        for j, c in _tendon_joints(mj, model, t2, what):
            k = _coord(model, j, dof_map, what)
            coef[k] = coef.get(k, 0.0) - float(d[1]) * c
    scale = max((abs(c) for c in coef.values()), default=0.0)
    coef = {k: c for k, c in coef.items() if abs(c) > 1e-12 * scale}
    if len(coef) < 2:
        raise ModelError(f"{what}: the tendon equality constrains fewer than two joints (a locked joint is not "
                         f"supported)")
    succ = max(sorted(coef), key=lambda k: abs(coef[k]))
    rest = [(k, -c / coef[succ]) for k, c in sorted(coef.items()) if k != succ]
    (pred, ratio), more = rest[0], tuple(rest[1:])
    return Coupling(ename, pred, succ, ratio, float(d[0]) / coef[succ], more)
