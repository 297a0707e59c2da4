"""URDF and URDF+ reader -> :class:`Robot`, and writing parameters back into a URDF.

Supported: ``revolute``/``continuous`` (R), ``prismatic`` (P), ``fixed`` (merged into the
parent body, inertias combined exactly), ``floating`` (F, root only), ``planar`` (urdfdom's: two
slides in the plane normal to ``<axis>``, then the rotation about it; a compound joint C, as
Pinocchio's planar joint for ``<axis xyz="0 0 1">``), and, as in Drake and
``../shared/CONVENTIONS.md``, ``spherical``/``ball`` (S) and ``universal`` (U, ``<axis>``
then ``<axis2>``). ``floating=True`` attaches the root link to the world by an F joint.

URDF+ (Chignoli et al. 2024): ``<loop name type>`` with ``<predecessor link>``/``<successor
link>`` (each with an ``<origin>`` in its link's frame; the two frames must coincide at
q = 0) and ``<axis>``; ``<coupling>`` (``q_successor = ratio * q_predecessor`` for the joints
of the two links); ``independent="false"`` on joints marks passive coordinates. The
``sucessor`` spelling and ``name=`` instead of ``link=`` are accepted with a warning.
Plain-URDF tools drop loops silently; this reader never does.

Drake's URDF extensions: undeclared namespace prefixes (``drake:``) are declared before parsing,
``<drake:joint>`` (ball, universal, planar) is read as a joint and ``<drake:ball_constraint>`` as
a spherical loop; every other namespaced element or attribute is dropped and counted in one
warning.

``<mimic multiplier offset>`` becomes a coupling (the follower is passive); a ``<mimic>`` of a
joint that does not exist is ignored with a warning, as urdfdom and Pinocchio do.
Not supported (clear errors): loops of unknown type.
Every error is one line naming the file, the element and the problem.
"""

from __future__ import annotations

import re
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..display import counted
from ..errors import ModelError, NoMovingBodiesError
from ..files import MODEL_MAX_BYTES, read_input_bytes
from ..model.bounds import check_magnitude
from ..model.builder import RobotBuilder, pose
from ..model.inertia import Inertia, check_inertia
from ..model.robot import Coupling, Robot, compound_screw

_TYPES = {"revolute": "R", "continuous": "R", "prismatic": "P", "fixed": "fixed", "floating": "F",
          "spherical": "S", "ball": "S", "universal": "U", "planar": "C"}
_LOOP_TYPES = {"revolute": "R", "continuous": "R", "prismatic": "P", "fixed": "fixed",
               "spherical": "S", "ball": "S", "universal": "U"}


class URDFWarning(UserWarning):
    """A tolerated irregularity in a URDF+ file (e.g. the ``sucessor`` spelling)."""


def _floats(text: str | None, n: int, what: str, default, kind: str | None = None) -> np.ndarray:
    """``n`` finite numbers from an attribute (``default`` when absent); ``kind``: bounded (model.bounds)."""
    if text is None:
        return np.asarray(default, dtype=float)
    hint = ("; unexpanded xacro/roslaunch substitution; run xacro first, or read the .xacro file itself "
            "(pip install 'baseparams[xacro]')" if "$(" in text or "${" in text else "")
    try:
        v = np.array([float(x) for x in text.split()])
    except ValueError:
        raise ModelError(f"{what}: expected {counted(n, 'number')}, got {text!r}{hint}") from None
    if v.shape != (n,) or not np.isfinite(v).all():  # ndarray methods: thousands of tiny arrays per file
        raise ModelError(f"{what}: expected {counted(n, 'finite number')}, got {text!r}")
    if kind is not None:
        check_magnitude(v, kind, what)
    return v


def _parse(path: Path, data: bytes | None = None, notes: list[str] | None = None) -> ET.Element:
    """The file's root element, tolerating what urdfdom, Pinocchio and pybullet tolerate.

    That is a UTF-8 byte-order mark, whitespace before ``<?xml``, whitespace and NUL bytes after
    the root element. Anything else malformed is a one-line error naming the file. ``data``: the
    document already read (an expanded xacro file), else the file is read. ``notes``: given, the
    note on namespaced content left out (:func:`_foreign_elements`) is appended to it too.
    """
    if data is None:
        data = read_input_bytes(path, MODEL_MAX_BYTES, error=ModelError)
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    body = data.lstrip(b" \t\r\n")
    skipped = data[:len(data) - len(body)].count(b"\n")  # for line numbers in messages
    body = body.rstrip(b" \t\r\n\x00")
    undeclared: list[str] = []
    try:
        root = ET.fromstring(body)
    except ET.ParseError as exc:
        root, undeclared = _declare_prefixes(body, exc)
        if root is None:
            line, col = getattr(exc, "position", (0, 0))
            msg = str(exc).split(":", 1)[0] if ": line" in str(exc) else str(exc)
            raise ModelError(f"{path}: malformed XML ({msg}: line {line + skipped}, column {col})") from None
    declared = {uri.decode(errors="replace"): prefix.decode(errors="replace")
                for prefix, uri in reversed(_DECLARATION.findall(body))}  # the first declaration of a URI names it
    note = _foreign_elements(root, path, undeclared, declared)
    if note and notes is not None:
        notes.append(note)
    return root


#: the namespace given to a prefix a file uses without declaring it (Drake's ``drake:``, read as Drake reads them)
_UNDECLARED = "urn:baseparams:undeclared:"
#: Drake's namespace, as its documentation declares it (``xmlns:drake="http://drake.mit.edu"``)
DRAKE_NAMESPACE = "http://drake.mit.edu"
_DECLARATION = re.compile(rb"xmlns:([A-Za-z_][\w.-]*)\s*=\s*[\"']([^\"']*)[\"']")


def _is_drake(uri: str) -> bool:
    """Whether a namespace is Drake's: its URI, or the ``drake`` prefix used undeclared (as Drake's files do)."""
    return uri.rstrip("/") == DRAKE_NAMESPACE or uri == f"{_UNDECLARED}drake"
_PREFIX_USE = re.compile(rb"<\s*/?\s*([A-Za-z_][\w.-]*):[A-Za-z_][\w.-]*|\s([A-Za-z_][\w.-]*):[A-Za-z_][\w.-]*\s*=")


def _declare_prefixes(body: bytes, exc: ET.ParseError) -> tuple[ET.Element | None, list[str]]:
    """The document parsed with its undeclared namespace prefixes declared (``drake:`` in Drake's URDFs).

    Only for "unbound prefix" errors: the prefixes used in tags and attribute names but never
    declared get a placeholder namespace on the root element. ``(None, [])`` when that is not the
    error or the document is still malformed.
    """
    if "unbound prefix" not in str(exc):
        return None, []
    declared = set(re.findall(rb"xmlns:([A-Za-z_][\w.-]*)\s*=", body))
    used = {(a or b).decode() for a, b in _PREFIX_USE.findall(body)}
    used = sorted(used - {d.decode() for d in declared} - {"xml", "xmlns"})
    start = re.search(rb"<(?![?!])[A-Za-z_][\w:.-]*", body)
    if not used or start is None:
        return None, []
    extra = b"".join(f' xmlns:{p}="{_UNDECLARED}{p}"'.encode() for p in used)
    try:
        return ET.fromstring(body[:start.end()] + extra + body[start.end():]), used
    except ET.ParseError:
        return None, []


def _foreign_elements(root: ET.Element, path: Path, undeclared: list[str], declared: dict[str, str]) -> str | None:
    """Drake's extensions read as Drake reads them, every other namespaced element or attribute dropped and counted.

    Namespaces are honoured as declared: only elements in Drake's namespace (:func:`_is_drake`) are
    read, ``<drake:joint>`` (ball, universal, planar and the standard types) as a ``<joint>`` and
    ``<drake:ball_constraint>`` as a spherical ``<loop>``. Any other element or attribute in a
    namespace -- Drake's collision filters, rotor inertia, gear ratio, hydroelastic properties,
    acceleration limits, or anything of another namespace (``<foo:joint>`` is not a URDF joint) --
    is removed, and one warning counts what was left out (and names the prefixes used without a
    declaration), the note returned (None: nothing to say). ``declared``: prefix of each declared
    namespace URI, for the messages.
    """
    dropped: dict[bool, dict[str, int]] = {True: {}, False: {}}  # Drake's, another namespace's: shown name, count

    def drop(tag: str, shown: str) -> None:
        part = dropped[_is_drake(tag[1:].split("}", 1)[0])]
        part[shown] = part.get(shown, 0) + 1

    stack = [root]
    while stack:  # a dropped element's own children are not counted again
        parent = stack.pop()
        for child in list(parent):
            if isinstance(child.tag, str) and child.tag.startswith("{"):
                uri, local = child.tag[1:].split("}", 1)
                if _is_drake(uri) and local == "ball_constraint":
                    parent.remove(child)
                    parent.append(_ball_constraint_loop(child, path))
                    continue
                if not (_is_drake(uri) and local == "joint" and _drake_joint(child, path)):
                    drop(child.tag, f"<{_shown_name(child.tag, declared)}>")
                    parent.remove(child)
                    continue
            stack.append(child)
    for elem in root.iter():
        for key in [k for k in elem.attrib if k.startswith("{")]:
            drop(key, _shown_name(key, declared))
            del elem.attrib[key]
    if not dropped[True] and not dropped[False] and not undeclared:
        return None
    note = _foreign_note(dropped[True], dropped[False], undeclared)
    warnings.warn(f"{path}: {note}", URDFWarning, stacklevel=4)
    return note


def _foreign_note(drake: dict[str, int], other: dict[str, int], undeclared: list[str]) -> str:
    """The one note on namespaced content: Drake's that describes no rigid body, then other namespaces'.

    A prefix ``drake`` bound to another namespace is among the others (classed by the namespace).
    Each count names what it counts, in its number (``1 element``, ``2 elements and 1 attribute``).
    """
    def listed(items: dict[str, int]) -> str:
        return ", ".join(f"{k} x{v}" if v > 1 else k for k, v in sorted(items.items()))

    def count(items: dict[str, int], adjective: str = "") -> tuple[str, bool]:
        elements = sum(v for k, v in items.items() if k.startswith("<"))  # an element is shown <tag>
        attributes = sum(items.values()) - elements
        said = [counted(n, what) for n, what in ((elements, f"{adjective}element"), (attributes, "attribute")) if n]
        return " and ".join(said), elements + attributes == 1

    prefixes = "namespace prefix" if len(undeclared) == 1 else "namespace prefixes"
    parts = [f"{prefixes} {', '.join(repr(p) for p in undeclared)} used without a declaration: read "
             f"leniently (as Drake does)"] if undeclared else []
    if drake:
        what, one = count(drake, "namespaced ")
        parts.append(f"{what} {'describes' if one else 'describe'} no rigid body and {'was' if one else 'were'} "
                     f"ignored: {listed(drake)}")
    if other:
        what, one = count(other)
        parts.append(f"{what} of other namespaces {'is' if one else 'are'} not URDF (nor Drake's) and "
                     f"{'was' if one else 'were'} ignored: {listed(other)}")
    return "; ".join(parts)


def _shown_name(tag: str, declared: dict[str, str]) -> str:
    """``{uri}local`` as the file wrote it: ``prefix:local`` (Drake's namespace as ``drake:``)."""
    uri, local = tag[1:].split("}", 1)
    if _is_drake(uri):
        return f"drake:{local}"
    if uri.startswith(_UNDECLARED):
        return f"{uri[len(_UNDECLARED):]}:{local}"
    return f"{declared[uri]}:{local}" if uri in declared else f"{{{uri}}}{local}"


#: the ``<drake:joint>`` types read (Drake's custom ones and the standard URDF ones); ``screw`` and
#: ``curvilinear`` have no counterpart
_DRAKE_JOINTS = ("ball", "universal", "planar", "revolute", "continuous", "prismatic", "fixed", "floating")


def _drake_joint(elem: ET.Element, path: Path) -> bool:
    """Turn a ``<drake:joint>`` into the ``<joint>`` it means, in place (True), or refuse it."""
    t = elem.get("type")
    if t not in _DRAKE_JOINTS:
        raise ModelError(f"{path}: <drake:joint name={elem.get('name')!r}>: Drake's {t!r} joint is not supported "
                         f"(ball, universal, planar and the URDF types {', '.join(_DRAKE_JOINTS[3:])} are)")
    elem.tag = "joint"
    for sub in elem.iter():  # Drake's own children as the joint's; another namespace's are dropped by the caller
        if isinstance(sub.tag, str) and sub.tag.startswith("{") and _is_drake(sub.tag[1:].split("}", 1)[0]):
            sub.tag = sub.tag.split("}", 1)[1]
    if t == "universal" and elem.find("axis2") is None:  # Drake: about the joint frame's x, then the moved y
        for old in elem.findall("axis"):
            elem.remove(old)
        ET.SubElement(elem, "axis", xyz="1 0 0")
        ET.SubElement(elem, "axis2", xyz="0 1 0")
    return True


def _ball_constraint_loop(elem: ET.Element, path: Path) -> ET.Element:
    """A ``<drake:ball_constraint>`` as the spherical URDF+ ``<loop>`` it is (point P on body A = point Q on B)."""
    part = {(c.tag.split("}", 1)[1] if c.tag.startswith("{") else c.tag): c for c in elem
            if isinstance(c.tag, str)}
    what = f"{path}: <drake:ball_constraint>"
    names, points = [], []
    for body, point in (("ball_constraint_body_A", "ball_constraint_p_AP"),
                        ("ball_constraint_body_B", "ball_constraint_p_BQ")):
        if body not in part or not part[body].get("name"):
            raise ModelError(f"{what}: needs <drake:{body} name=...>")
        names.append(part[body].get("name"))
        points.append(part[point].get("value", "0 0 0") if point in part else "0 0 0")
    loop = ET.Element("loop", name=f"ball_constraint_{names[0]}_{names[1]}", type="spherical")
    for tag, name, xyz in (("predecessor", names[0], points[0]), ("successor", names[1], points[1])):
        side = ET.SubElement(loop, tag, link=name)
        ET.SubElement(side, "origin", xyz=xyz)
    return loop


def _origin(elem: ET.Element | None, what: str) -> np.ndarray:
    if elem is None:
        return np.eye(4)
    return pose(_floats(elem.get("xyz"), 3, f"{what} <origin xyz>", (0, 0, 0), "length"),
                _floats(elem.get("rpy"), 3, f"{what} <origin rpy>", (0, 0, 0), "angle"))


def _inertial(link: ET.Element, what: str, check: bool = True, strict: bool = False) -> Inertia | None:
    """The link's ``<inertial>`` (None if absent).

    ``check``: warn (``strict``: raise) when it is physically infeasible. Links fixed to the
    world are read unchecked: they never move.
    """
    inl = link.find("inertial")
    if inl is None:
        return None
    m = inl.find("mass")
    mass = float(_floats(m.get("value") if m is not None else None, 1, f"{what} <mass value>", (0.0,), "mass")[0])
    it = inl.find("inertia")
    if it is None:
        j = np.zeros((3, 3))
    else:
        v = {}
        for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
            v[k] = float(_floats(it.get(k), 1, f"{what} <inertia {k}>", (0.0,), "inertia")[0])
        j = np.array([[v["ixx"], v["ixy"], v["ixz"]], [v["ixy"], v["iyy"], v["iyz"]], [v["ixz"], v["iyz"], v["izz"]]])
    if check:
        check_inertia(mass, j, what, strict=strict)
    frame = _origin(inl.find("origin"), f"{what} <inertial>")
    return Inertia(mass, com=(0.0, 0.0, 0.0), inertia=j, frame=frame)


def _link_ref(elem: ET.Element, what: str, path: Path, stacklevel: int = 4) -> str:
    name = elem.get("link")
    if name is None and elem.get("name") is not None:
        warnings.warn(f"{what}: 'name=' used instead of 'link='; accepted", URDFWarning, stacklevel=stacklevel)
        name = elem.get("name")
    if not name:
        raise ModelError(f"{what}: missing link attribute")
    return name


class _Index(NamedTuple):
    """The file's links and joints, indexed: what the depth-first build walks."""

    links: dict[str, ET.Element]
    joints: dict[str, ET.Element]
    parent_of: dict[str, str]  # child link -> name of its parent joint
    children: dict[str, list[ET.Element]]  # link -> joints hanging from it, in file order
    mimics: dict[str, tuple[str, float, float]]  # follower joint -> (leader, multiplier, offset)


def load_urdf(path: str | Path, floating: bool = False, gravity=(0.0, 0.0, -9.81),
              name: str | None = None, strict_inertia: bool = False, data: bytes | None = None,
              edit=None) -> Robot:
    """Read a URDF / URDF+ file into a :class:`Robot` (see the module doc).

    Physically infeasible inertias of moving links are warnings
    (:class:`~baseparams.model.inertia.InertiaWarning`), or errors with ``strict_inertia``; links
    fixed to the world are never checked.

    Parameters
    ----------
    path : str or Path
        The URDF or URDF+ file.
    floating : bool, optional
        Attach the root link to the world by an F joint (``root_joint``); ignored when the file
        has its own ``floating`` joint at the root.
    gravity : array_like, shape ``(3,)``, optional
        Gravity in the world frame, m/s^2.
    name : str, optional
        The robot's name; default the ``<robot name>`` attribute, else the file's stem.
    strict_inertia : bool, optional
        Physically infeasible inertias of moving links are errors instead of warnings.
    data : bytes, optional
        The document, already read (a xacro file expanded by :mod:`baseparams.io.xacro_in`);
        messages still name ``path``. Default: read ``path``.
    edit : callable, optional
        Called with the document's root element before the robot is built (it may change
        attribute values: :mod:`baseparams.io.snapfile` sets rounded right angles exact).

    Returns
    -------
    Robot
        The robot at the file's q = 0 (fixed links merged into their parent bodies); with loops
        or couplings, ``q_box`` is the independent joints' limits capped at +-1 (rad or m).
        Loops are not assembled here (:func:`baseparams.io.load.load_file` does that).

    Raises
    ------
    ModelError
        Malformed XML or an unsupported or inconsistent element (one line naming the file, the
        element and the problem); :class:`NoMovingBodiesError` when no link moves.

    Warns
    -----
    URDFWarning
        Tolerated irregularities (``sucessor``, ``name=`` for ``link=``, ignored mimics).
    InertiaWarning
        Physically infeasible inertias of moving links (without ``strict_inertia``).
    """
    path = Path(path)
    foreign: list[str] = []
    root = _parse(path, data, foreign)
    if edit is not None:
        edit(root)
    try:
        return _robot_of(root, path, floating, gravity, name, strict_inertia)
    except ModelError as exc:  # what was left out may be why: said with the refusal (the warning is lost with it)
        if not foreign:
            raise
        raise type(exc)(f"{exc} (note: {foreign[0]})") from None


def _robot_of(root: ET.Element, path: Path, floating: bool, gravity, name: str | None,
              strict_inertia: bool) -> Robot:
    """:func:`load_urdf` once the document is parsed: the robot its ``<robot>`` element describes."""
    if root.tag != "robot":
        raise ModelError(f"{path}: root element is <{root.tag}>, expected <robot>")
    links = _index_links(root, path)
    ix = _index_joints(root, links, path)
    _drop_ignored_mimics(ix, path)
    base = _root_link(ix, path)
    b = RobotBuilder(name or root.get("name") or path.stem, gravity=gravity)
    if floating and any(j.get("type") == "floating" for j in ix.children[base]):
        floating = False  # the file has its own floating joint at the root
    limits = _add_root(b, ix, base, floating, path, strict_inertia)
    _add_tree(b, ix, base, floating, limits, path, strict_inertia)
    has_loops = _add_loops(b, root, links, path)
    couplings = _read_couplings(root, path) + _mimic_couplings(ix)
    if has_loops or couplings:
        b.q_box = _sampling_box(limits)
    try:
        robot = b.build()
    except ModelError as exc:  # the builder names the robot; the file is named here
        raise type(exc)(f"{path}: {exc}") from None
    if couplings:
        robot = _with_couplings(robot, couplings, path)
    robot = _with_limits(robot, ix, path)
    if has_loops and not any("independent" in j.attrib for j in ix.joints.values()):
        robot = _independent_from_loops(robot, path)
    return robot


def _independent_from_loops(robot: Robot, path: Path) -> Robot:
    """A loop robot whose file marks no joint ``independent`` (Drake's ball constraints): chosen from the loops.

    URDF+ makes every joint independent unless marked; with loops that over-determines the passive
    ones (no sample closes them). As for MJCF, the independent coordinates are chosen from the
    constraints at q = 0 (:func:`~baseparams.kinematics.loops.choose_independent`, mimicking joints
    passive first), with a note.
    """
    from ..kinematics.loops import choose_independent

    chosen = choose_independent(robot, set(robot.actuated))
    names = [chosen.joint_names[chosen.dof_body[j]] for j in chosen.actuated]
    warnings.warn(f"{path}: no joint says which coordinates are independent (URDF+ independent=\"false\" on the "
                  f"passive ones) and the loops ({', '.join(lj.name for lj in robot.loops)}) tie them: chosen from the "
                  f"constraints at q = 0, independent {names}", URDFWarning, stacklevel=3)
    return chosen


def _index_links(root: ET.Element, path: Path) -> dict[str, ET.Element]:
    """The ``<link>`` elements by name: each named, no duplicates, at least one."""
    links: dict[str, ET.Element] = {}
    for ln in root.findall("link"):
        lname = ln.get("name")
        if not lname:
            raise ModelError(f"{path}: a <link> has no name")
        if lname in links:
            raise ModelError(f"{path}: duplicate link {lname!r}")
        links[lname] = ln
    if not links:  # urdfdom refuses it; here it is a robot with nothing to identify
        raise NoMovingBodiesError(f"{path}: no <link> elements: no moving links")
    return links


def _index_joints(root: ET.Element, links: dict[str, ET.Element], path: Path) -> _Index:
    """Every ``<joint>`` checked and indexed.

    Checked: name, parent and child links, one parent per link, mimic, type.
    """
    ix = _Index(links, {}, {}, {k: [] for k in links}, {})
    for jt in root.findall("joint"):
        jname = jt.get("name")
        what = f"{path}: <joint name={jname!r}>"
        if not jname:
            raise ModelError(f"{path}: a <joint> has no name")
        if jname in ix.joints:
            raise ModelError(f"{path}: duplicate joint {jname!r}")
        ix.joints[jname] = jt
        pl, cl = _joint_links(jt, links, what)
        if cl in ix.parent_of:
            raise ModelError(f"{what}: link {cl!r} already has parent joint {ix.parent_of[cl]!r} "
                             f"(a second parent or a cycle: close loops with <loop>)")
        ix.parent_of[cl] = jname
        ix.children[pl].append(jt)
        mim = jt.find("mimic")
        if mim is not None:
            ix.mimics[jname] = _mimic(mim, what)
        t = jt.get("type")
        if t not in _TYPES:
            raise ModelError(f"{what}: unknown or unsupported joint type {t!r}")
    return ix


def _joint_links(jt: ET.Element, links: dict[str, ET.Element], what: str) -> tuple[str, str]:
    """``(parent link, child link)`` of a joint, both existing links."""
    p, c = jt.find("parent"), jt.find("child")
    if p is None or c is None or not p.get("link") or not c.get("link"):
        raise ModelError(f"{what}: needs <parent link> and <child link>")
    pl, cl = p.get("link"), c.get("link")
    for ref in (pl, cl):
        if ref not in links:
            raise ModelError(f"{what}: unknown link {ref!r}")
    return pl, cl


def _mimic(mim: ET.Element, what: str) -> tuple[str, float, float]:
    """``(leader joint, multiplier, offset)`` of a ``<mimic>``."""
    leader = mim.get("joint")
    if not leader:
        raise ModelError(f"{what}: <mimic> needs a joint attribute")
    mult = float(_floats(mim.get("multiplier"), 1, f"{what} <mimic multiplier>", (1.0,), "axis")[0])
    off = float(_floats(mim.get("offset"), 1, f"{what} <mimic offset>", (0.0,), "length")[0])
    return leader, mult, off


def _drop_ignored_mimics(ix: _Index, path: Path) -> None:
    """Drop, with a warning each, the mimics that cannot be kept.

    Those of unknown joints (as urdfdom and Pinocchio do) and those involving a fixed joint.
    """
    for jname, (leader, _, _) in list(ix.mimics.items()):
        if leader not in ix.joints:  # urdfdom and Pinocchio ignore it: say so, once
            warnings.warn(f"{path}: <joint name={jname!r}> <mimic>: ignored (unknown joint {leader!r}); "
                          f"{jname!r} moves freely", URDFWarning, stacklevel=3)
            del ix.mimics[jname]
        elif "fixed" in (ix.joints[jname].get("type"), ix.joints[leader].get("type")):
            warnings.warn(f"{path}: <joint name={jname!r}> <mimic>: ignored (a fixed joint cannot mimic or be "
                          f"mimicked)", URDFWarning, stacklevel=3)
            del ix.mimics[jname]


def _root_link(ix: _Index, path: Path) -> str:
    """The one link without a parent joint."""
    roots = [k for k in ix.links if k not in ix.parent_of]
    if len(roots) != 1:
        if not roots:
            raise ModelError(f"{path}: no root link: the joints form a cycle")
        raise ModelError(f"{path}: several root links {roots[:5]}: the tree is not connected")
    return roots[0]


def _add_root(b: RobotBuilder, ix: _Index, base: str, floating: bool, path: Path,
              strict_inertia: bool) -> list[tuple[float, float]]:
    """Add the root link, floating (an F joint ``root_joint``) or as the fixed base.

    Returns the joint limits so far (six unbounded ones when floating).
    """
    if floating:
        b.add_link(base, joint="F", inertia=_inertial(ix.links[base], f"{path}: <link name={base!r}>",
                                                     strict=strict_inertia),
                   joint_name="root_joint")
        return [(-np.inf, np.inf)] * 6
    b.add_link(base, joint="fixed")  # the root link is the fixed base (a frame)
    return []


def _add_tree(b: RobotBuilder, ix: _Index, base: str, floating: bool, limits: list[tuple[float, float]],
              path: Path, strict_inertia: bool) -> None:
    """Add every joint and its child link, depth first from ``base`` in file order.

    Appends the independent joints' limits to ``limits``. Every link must be reached, once.
    """
    world_fixed = set() if floating else {base}  # links welded to the world: their inertia never matters
    seen = {base}
    stack = [(base, c) for c in reversed(ix.children[base])]
    while stack:
        plink, jt = stack.pop()
        jname = jt.get("name")
        what = f"{path}: <joint name={jname!r}>"
        cl = jt.find("child").get("link")
        if cl in seen:
            raise ModelError(f"{what}: link {cl!r} reached twice (cycle)")
        seen.add(cl)
        t = _TYPES[jt.get("type")]
        if t == "F" and (plink != base or floating):
            raise ModelError(f"{what}: a floating joint is only supported at the root")
        axis, axis2 = _joint_axes(jt, t, what) if t != "C" else (_planar_axes(jt, what), None)
        indep = _independent(jt, jname in ix.mimics, what)
        if t != "fixed" and indep in ("true", "1") and not (t == "R" and jname in ix.mimics):
            limits += _joint_limits(jt, t, what)
        parent_name = None if (plink == base and not floating) else plink
        if t == "fixed" and plink in world_fixed:
            world_fixed.add(cl)
        b.add_link(cl, parent=parent_name if parent_name is not None else base, joint=t,
                   origin=_origin(jt.find("origin"), what), axis=axis, axis2=axis2,
                   inertia=_inertial(ix.links[cl], f"{path}: <link name={cl!r}>", check=cl not in world_fixed,
                                     strict=strict_inertia), joint_name=jname,
                   actuated=None if t == "fixed" else indep in ("true", "1"))
        stack.extend((cl, c) for c in reversed(ix.children[cl]))
    unreached = [k for k in ix.links if k not in seen]
    if unreached:
        raise ModelError(f"{path}: links {unreached[:5]} are not connected to the root link {base!r} "
                         f"(a cycle of joints? close loops with <loop>)")


def _joint_axes(jt: ET.Element, t: str, what: str) -> tuple[np.ndarray, np.ndarray | None]:
    """``(axis, axis2)`` of a joint of type ``t`` (``axis2`` only for U, which needs it)."""
    axis_el = jt.find("axis")
    axis = _floats(axis_el.get("xyz") if axis_el is not None else None, 3, f"{what} <axis xyz>", (1, 0, 0), "axis")
    axis2_el = jt.find("axis2")
    axis2 = _floats(axis2_el.get("xyz") if axis2_el is not None else None, 3, f"{what} <axis2 xyz>",
                    (0, 1, 0), "axis") if t == "U" else None
    if t in ("R", "P", "U") and np.linalg.norm(axis) < 1e-12:
        raise ModelError(f"{what}: zero joint axis")
    if t == "U" and axis2_el is None:
        raise ModelError(f"{what}: a universal joint needs <axis2>")
    return axis, axis2


def _planar_axes(jt: ET.Element, what: str) -> np.ndarray:
    """A ``planar`` joint as urdfdom defines it: motion in the plane normal to ``<axis>`` (default ``1 0 0``).

    Three screws in the joint frame (a compound joint C): slides along ``e1`` and ``e2`` spanning
    the plane, then the rotation about ``<axis>`` through the moved origin, i.e. ``(x, y, theta)``
    as Pinocchio's planar joint (``e1, e2 = x, y`` for ``<axis xyz="0 0 1">``). Pinocchio ignores
    ``<axis>`` (always the x-y plane): another axis is read as urdfdom reads it, with a warning.
    """
    axis_el = jt.find("axis")
    n = _floats(axis_el.get("xyz") if axis_el is not None else None, 3, f"{what} <axis xyz>", (1, 0, 0), "axis")
    if np.linalg.norm(n) < 1e-12:
        raise ModelError(f"{what}: zero joint axis")
    n = n / np.linalg.norm(n)
    if not np.allclose(n, (0, 0, 1), atol=1e-12):
        given = "no <axis>: urdfdom's default 1 0 0" if axis_el is None else f"<axis xyz={axis_el.get('xyz')!r}>"
        warnings.warn(f"{what}: planar joint with {given}: the plane normal to it (as urdfdom); Pinocchio reads "
                      f"every planar joint in the joint frame's x-y plane", URDFWarning, stacklevel=5)
    e1 = np.array([0.0, 1.0, 0.0]) if abs(n[0]) > 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = e1 - (e1 @ n) * n
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n, e1)
    return np.stack([compound_screw(e1, slide=True), compound_screw(e2, slide=True), compound_screw(n)])


def _independent(jt: ET.Element, mimicking: bool, what: str) -> str:
    """The joint's ``independent`` attribute, normalised (default false for a mimicking joint)."""
    indep = jt.get("independent", "false" if mimicking else "true").strip().lower()
    if indep not in ("true", "false", "1", "0"):
        raise ModelError(f"{what}: independent must be true or false, got {indep!r}")
    return indep


def _joint_limits(jt: ET.Element, t: str, what: str) -> list[tuple[float, float]]:
    """The limits of an independent joint's coordinates (unbounded but for R and P)."""
    if t not in ("R", "P"):
        return [(-np.inf, np.inf)] * {"U": 2, "S": 3, "F": 6, "C": 3}[t]
    lim = jt.find("limit")
    lo = _floats(lim.get("lower") if lim is not None else None, 1, f"{what} <limit lower>", (-np.inf,))[0]
    hi = _floats(lim.get("upper") if lim is not None else None, 1, f"{what} <limit upper>", (np.inf,))[0]
    return [(lo, hi)]


def _with_limits(robot: Robot, ix: _Index, path: Path) -> Robot:
    """The robot with :attr:`Robot.limits` from the ``<limit>`` of its revolute and prismatic joints.

    ``lower``/``upper`` (not for continuous joints), ``velocity``, ``effort``; a missing attribute, a
    zero velocity or effort (a placeholder in many files) and any coordinate of another joint type
    are NaN (unknown), and so are position limits with lower > upper (with a warning). No joint with a
    ``<limit>`` and no continuous joint: ``limits`` stays None (a continuous joint's NaN position limits
    say it has none: any number of turns).
    """
    from dataclasses import replace

    out = np.full((robot.dof, 4), np.nan)
    found = False
    for i, (jname, k) in enumerate(zip(robot.joint_names, robot.q_index)):
        jt = ix.joints.get(jname)
        lim = None if jt is None or robot.jtype[i] not in ("R", "P") else jt.find("limit")
        if lim is None:
            found |= jt is not None and jt.get("type") == "continuous"  # declared without position limits
            continue
        found = True
        what = f"{path}: <joint name={jname!r}> <limit"
        keys = ("velocity", "effort") if jt.get("type") == "continuous" else ("lower", "upper", "velocity", "effort")
        for key in keys:
            v = float(_floats(lim.get(key), 1, f"{what} {key}>", (np.nan,))[0])
            out[k, ("lower", "upper", "velocity", "effort").index(key)] = np.nan if key in keys[-2:] and v == 0 else v
        if out[k, 0] > out[k, 1]:
            warnings.warn(f"{what}>: lower {out[k, 0]} > upper {out[k, 1]}; position limits ignored", URDFWarning,
                          stacklevel=3)
            out[k, :2] = np.nan
    return replace(robot, limits=out) if found else robot


def _pred_succ(elem: ET.Element, what: str, tag: str, path: Path) -> tuple[ET.Element, ET.Element]:
    """The ``<predecessor>`` and ``<successor>`` of a ``<loop>`` or ``<coupling>``.

    ``sucessor`` is accepted with a warning; ``tag`` is the element as the warning names it.
    """
    pred, succ = elem.find("predecessor"), elem.find("successor")
    if succ is None and elem.find("sucessor") is not None:
        warnings.warn(f"{path}: {tag}: 'sucessor' spelling accepted", URDFWarning, stacklevel=4)
        succ = elem.find("sucessor")
    if pred is None or succ is None:
        raise ModelError(f"{what}: needs <predecessor> and <successor>")
    return pred, succ


def _add_loops(b: RobotBuilder, root: ET.Element, links: dict[str, ET.Element], path: Path) -> bool:
    """Add the URDF+ ``<loop>`` closures; whether there are any."""
    loop_elems = root.findall("loop")
    for lp in loop_elems:
        lname = lp.get("name", "?")
        what = f"{path}: <loop name={lname!r}>"
        t = lp.get("type")
        if t not in _LOOP_TYPES:
            raise ModelError(f"{what}: unknown or unsupported loop type {t!r}")
        pred, succ = _pred_succ(lp, what, what.split(": ", 1)[1], path)
        pl = _link_ref(pred, f"{what} <predecessor>", path, stacklevel=5)
        sl = _link_ref(succ, f"{what} <successor>", path, stacklevel=5)
        for ref in (pl, sl):
            if ref not in links:
                raise ModelError(f"{what}: unknown link {ref!r}")
        axis_el = lp.find("axis")
        axis = _floats(axis_el.get("xyz") if axis_el is not None else None, 3, f"{what} <axis xyz>", (1, 0, 0), "axis")
        axis2_el = lp.find("axis2")
        axis2 = _floats(axis2_el.get("xyz") if axis2_el is not None else None, 3, f"{what} <axis2 xyz>", (0, 1, 0),
                        "axis")
        b.add_loop(lname, _LOOP_TYPES[t], parent=pl, child=sl, origin=_origin(pred.find("origin"), what),
                   axis=axis, axis2=axis2 if _LOOP_TYPES[t] == "U" else None,
                   child_origin=_origin(succ.find("origin"), what))
    return bool(loop_elems)


def _read_couplings(root: ET.Element, path: Path) -> list[tuple[str, str, str, float, float]]:
    """The URDF+ ``<coupling>`` elements as ``(name, predecessor link, successor link, ratio, 0)``."""
    couplings = []
    for cp in root.findall("coupling"):
        cname = cp.get("name", "?")
        what = f"{path}: <coupling name={cname!r}>"
        pred, succ = _pred_succ(cp, what, f"<coupling name={cname!r}>", path)
        ratio_el = cp.find("ratio")
        ratio = float(_floats(ratio_el.get("value") if ratio_el is not None else None, 1, f"{what} <ratio value>",
                              (1.0,), "axis")[0])
        couplings.append((cname, _link_ref(pred, f"{what} <predecessor>", path, stacklevel=5),
                          _link_ref(succ, f"{what} <successor>", path, stacklevel=5), ratio, 0.0))
    return couplings


def _mimic_couplings(ix: _Index) -> list[tuple[str, str, str, float, float]]:
    """The kept mimics as couplings ``(mimic:follower, leader's link, follower's link, mult, off)``."""
    return [(f"mimic:{jname}", ix.joints[leader].find("child").get("link"),
             ix.joints[jname].find("child").get("link"), mult, off)
            for jname, (leader, mult, off) in ix.mimics.items()]


def _sampling_box(limits: list[tuple[float, float]]) -> np.ndarray:
    """The independent joints' limits as a sampling box around q = 0, capped at +-1 (rad or m).

    The cap keeps continuation on one assembly mode; a joint whose limits do not straddle 0 gets
    ``(-0.3, 0.3)``.
    """
    return np.array([[max(lo, -1.0), min(hi, 1.0)] if lo < 0 < hi else [-0.3, 0.3] for lo, hi in limits])


def _with_couplings(robot: Robot, couplings, path: Path) -> Robot:
    from dataclasses import replace

    out = []
    qi = robot.q_index
    for cname, pl, sl, ratio, offset in couplings:
        what = f"{path}: <coupling name={cname!r}>"
        idx = []
        for ln in (pl, sl):
            if ln not in robot.names:
                raise ModelError(f"{what}: link {ln!r} has no joint of its own (fixed or the base)")
            i = robot.names.index(ln)
            if robot.ndofs[i] != 1:
                raise ModelError(f"{what}: link {ln!r} must hang from a 1-dof joint")
            idx.append(int(qi[i]))
        out.append(Coupling(cname, idx[0], idx[1], ratio, offset))
    return replace(robot, couplings=tuple(out))


#: what each drive parameter kind is, and its units for a revolute and a prismatic joint
_DRIVE_KINDS = {"Ia": ("rotor inertia (armature)", "kg m^2", "kg"), "Fv": ("viscous friction", "N m s/rad", "N s/m"),
                "Fc": ("Coulomb friction", "N m", "N"), "Fo": ("torque offset", "N m", "N"),
                "Iam": ("rotor inertia", "kg m^2", "kg"), "Fvm": ("viscous friction", "N m s/rad", "N s/m"),
                "Fcm": ("Coulomb friction", "N m", "N")}
#: the drive kinds a URDF ``<dynamics>`` holds, and the attribute each goes to
_URDF_DYNAMICS = {"Fv": "damping", "Fc": "friction"}


def _num(v: float, digits: int = 10) -> str:
    """``v`` at ``digits`` significant digits, without float-repr noise (``-0`` written ``0``)."""
    text = f"{float(v):.{digits}g}"
    return "0" if float(text) == 0 else text


def write_urdf(source: str | Path, dest: str | Path, robot: Robot, params, convention: str, *,
               drives: dict | None = None, couplings=(), inputs=(), base_rotation=None) -> list[str]:
    """Write ``source`` to ``dest`` with every moving body's ``<inertial>`` set to ``params``.

    Only values change: the file is edited in place (:mod:`baseparams.io.xmledit`), so the
    output keeps the source's elements, their order, comments, blank lines, indentation and
    attribute quoting, and a diff of the two shows the changed attribute values (and the
    ``<dynamics>`` elements and comments added). Numbers are written at 10 significant digits
    (more for a body that needs them to re-read exactly); an ``<inertial>`` keeps its
    ``<origin rpy>`` (the inertia is written in that frame).

    Exactly the requested bodies or nothing: each body's ``<inertial>`` (mass, centre of mass,
    inertia about it) is re-read as :func:`load_urdf` reads it and must give the requested
    pseudo-inertia to ~1e-9 of the body's scale; a body a URDF ``<inertial>`` cannot represent
    (mass <= 0 with a nonzero first moment, a mass so small that the centre of mass lands
    absurdly far away) raises :class:`ModelError` naming the file and the link, and nothing is
    written. Links merged into a moving body by fixed joints get zero inertia (their share is
    in the body's values); links welded to the world (the fixed root and links fixed to it)
    are not part of any body and keep their ``<inertial>`` untouched.

    Drive terms: viscous ``Fv`` and Coulomb ``Fc`` friction go to the joint's ``<dynamics
    damping friction>`` (the element is added when missing; a kind not given keeps the
    source's attribute). What a URDF cannot hold (rotor inertia / armature ``Ia``, torque
    offsets ``Fo``, coupled motors) is written as an XML comment inside each joint
    (``<!-- baseparams: ... -->``, replacing an earlier one) and summed up in the returned notes.

    Parameters
    ----------
    source : str or Path
        The URDF file ``robot`` was read from (every body must be one of its links).
    dest : str or Path
        The file written (atomically; never one of ``source`` and ``inputs``).
    robot : Robot
        The robot read from ``source`` (``n`` moving bodies).
    params : array_like, shape ``(10 n,)``
        The inertial parameters, ten per body, in ``convention``.
    convention : str
        The parameters' convention (:class:`~baseparams.enums.Convention`), which must be given:
        link-frame conventions are in each body's joint frame, as read; ``paper`` in the world
        frame at q = 0.
    drives : dict, optional
        ``{joint name: {"Ia", "Fv", "Fc", "Fo": float or None}}`` (missing or None: not
        identified), in the joint's units (N m s/rad, N m, kg m^2 for a revolute joint).
    couplings : iterable of dict
        Coupled motors, ``{"name", "joints": {joint: weight}, "Iam", "Fvm", "Fcm"}`` (as
        :meth:`baseparams.ident.Identification.couplings`): noted in each joint's comment.
    inputs : iterable of str or Path
        Further input files ``dest`` must not overwrite (the log, ...).
    base_rotation : array_like, shape ``(3, 3)``, optional
        A rotation of the robot in the world (a mounting tilt,
        :meth:`baseparams.ident.terms.tilt.Tilt.base_rotation`): a URDF's root link is fixed, so
        every joint hanging from it has its ``<origin>`` rotated about the root's frame (the root
        link's own inertia does not move the joints).

    Returns
    -------
    list of str
        Notes: the ``<dynamics>`` written and what URDF cannot hold (empty without drive terms).

    Raises
    ------
    ModelError
        ``params`` of the wrong size, a body that is not a link of ``source``, a joint of
        ``drives`` that is not in it, a negative friction, or a body a URDF ``<inertial>``
        cannot represent (nothing is written then).
    BaseparamsError
        ``dest`` is an input or cannot be written.
    """
    from ..files import write_text
    from . import xmledit

    source, dest = Path(source), Path(dest)
    root = _parse(source)
    try:
        n_body = robot.with_parameters(params, convention).N_body  # the robot's own conversion to body frames
    except ModelError as exc:
        raise ModelError(f"{dest}: {exc}") from None
    links = {ln.get("name"): ln for ln in root.findall("link")}
    parent_link = {}
    for jt in root.findall("joint"):
        c, pl = jt.find("child"), jt.find("parent")
        if c is not None and pl is not None:
            parent_link[c.get("link")] = (pl.get("link"), jt.get("type"))
    missing = [b for b in robot.names if b not in links]
    if missing:
        raise ModelError(f"{dest}: bodies {missing[:5]} of robot {robot.name!r} are not links of {source}")
    bodies = set(robot.names)
    merged = []  # links whose inertia is part of a moving body
    for ln_name in links:
        k = ln_name
        while k not in bodies and k in parent_link and parent_link[k][1] == "fixed":
            k = parent_link[k][0]
        if ln_name not in bodies and k in bodies:
            merged.append(ln_name)
    try:
        text = source.read_bytes().decode("utf-8")
    except UnicodeDecodeError:
        raise ModelError(f"{source}: not UTF-8 text; urdf= edits UTF-8 files only") from None
    doc = xmledit.parse(text, str(source))
    edit = xmledit.Editor(text)
    nodes = {ln.attrs.get("name"): ln for ln in doc.findall("link")}
    for i, name in enumerate(robot.names):
        what = f"{dest}: <link name={name!r}>"
        _edit_inertial(edit, nodes[name], _exact_inertial(n_body[i], what, _inertial_rotation(links[name], what)))
    for name in merged:
        if links[name].find("inertial") is not None:
            zero = {"mass": "0", "xyz": "0 0 0", "inertia": dict.fromkeys(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
                                                                          "0")}
            _edit_inertial(edit, nodes[name], zero)
    notes = _edit_drives(edit, doc, source, drives or {}, list(couplings))
    notes += [] if base_rotation is None else _rotate_base(edit, doc, root, np.asarray(base_rotation, float), dest)
    out = edit.text()
    back = ET.fromstring(out.lstrip("\ufeff \t\r\n").rstrip(" \t\r\n\x00").encode("utf-8"))
    back_links = {ln.get("name"): ln for ln in back.findall("link")}
    for i, name in enumerate(robot.names):  # what the reader gets from the text written
        got = _inertial(back_links[name], name, check=False)
        err = np.abs((got.pseudo() if got is not None else 0.0) - n_body[i]).max()
        if not err <= 1e-9 * max(float(np.abs(n_body[i]).max()), np.finfo(float).tiny):
            raise ModelError(f"{dest}: <link name={name!r}>: the edited file re-reads with error {err:.3g}; "
                             f"not written")  # pragma: no cover - a bug of the editor
    write_text(dest, out, inputs=[source, *inputs], what="urdf=")
    return notes


def _rotate_base(edit, doc, root: ET.Element, rot: np.ndarray, dest) -> list[str]:
    """Rotate the ``<origin>`` of every joint whose parent is the root link by ``rot`` (about the root's frame)."""
    from ..model.snap import rpy

    children = {jt.find("child").get("link") for jt in root.findall("joint") if jt.find("child") is not None}
    roots = [ln.get("name") for ln in root.findall("link") if ln.get("name") not in children]
    if len(roots) != 1:
        raise ModelError(f"{dest}: the mounting tilt needs one root link, found {roots[:5]}")
    joints = [(el, node) for el, node in zip(root.findall("joint"), doc.findall("joint"))
              if el.find("parent") is not None and el.find("parent").get("link") == roots[0]]
    for el, node in joints:
        t = _origin(el.find("origin"), f"{dest}: <joint name={el.get('name')!r}>")
        rot4 = np.eye(4)
        rot4[:3, :3] = rot
        new = rot4 @ t
        xyz = " ".join(f"{v:.12g}" for v in new[:3, 3])
        ang = " ".join(f"{v:.12g}" for v in rpy(new[:3, :3]))
        origin = node.find("origin")
        if origin is not None:
            edit.set(origin, xyz=xyz, rpy=ang)
        else:
            edit.append(node, [f'<origin xyz="{xyz}" rpy="{ang}"/>'])
    angle = float(np.degrees(np.arccos(np.clip((np.trace(rot) - 1) / 2, -1.0, 1.0))))
    return [f"--urdf: the mounting tilt ({angle:.3g} degree) written as the rotation of the joints on the root link "
            f"{roots[0]!r} ({', '.join(repr(e.get('name')) for e, _ in joints)}): a URDF's gravity is the world's"]


def _inertial_rotation(link: ET.Element, what: str) -> np.ndarray:
    """The rotation of the link's ``<inertial><origin rpy>`` (identity when absent)."""
    inl = link.find("inertial")
    return _origin(inl.find("origin") if inl is not None else None, what)[:3, :3]


def _exact_inertial(n: np.ndarray, what: str, rot: np.ndarray | None = None) -> dict:
    """The attribute values of a URDF ``<inertial>`` that re-reads as ``n``.

    ``n`` is a pseudo-inertia in the link frame; ``rot`` the rotation of the ``<inertial>``'s
    frame (its ``<origin rpy>``, kept: the inertia is written in that frame). Numbers are
    written at 10 significant digits, more when the body needs them to re-read to 1e-9 of its
    scale; a body no precision reproduces is a :class:`ModelError`.

    Returns ``{"mass": str, "xyz": str, "inertia": {"ixx": str, ...}}``.
    """
    from ..model import inertia as I

    rot = np.eye(3) if rot is None else rot
    m, h, j_o = I.split(n)
    m = float(m)
    scale = float(np.abs(n).max())
    if not np.all(np.isfinite(n)):
        raise ModelError(f"{what}: cannot write a pseudo-inertia with NaN or inf")
    if m > 0:
        c = h / m
        j_c = j_o - m * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
    else:
        c, j_c = np.zeros(3), j_o
    hn = float(np.linalg.norm(h))
    if m <= 0 and hn > 1e-9 * max(scale, np.finfo(float).tiny):
        raise ModelError(f"{what}: mass {m:.6g} with a nonzero first moment (|m c| = {hn:.3g}) has no URDF "
                         f"<inertial>: the centre of mass of a body with mass <= 0 is undefined")
    j = rot.T @ j_c @ rot
    tiny = 1e-13 * max(float(np.abs(j).max()), np.finfo(float).tiny)
    j = np.where(np.abs(j) < tiny, 0.0, j)  # rounding residue of exact zeros
    c = np.where(np.abs(c) < 1e-13 * max(float(np.abs(c).max()), np.finfo(float).tiny), 0.0, c)
    frame = np.eye(4)
    frame[:3, :3] = rot
    err = np.inf
    for digits in (10, 12, 14, 17):
        vals = {"mass": _num(m, digits), "xyz": " ".join(_num(v, digits) for v in c),
                "inertia": {k: _num(j[a, b], digits) for k, (a, b) in
                            zip(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"), ((0, 0), (0, 1), (0, 2), (1, 1), (1, 2),
                                                                             (2, 2)))}}
        jj = np.array([[float(vals["inertia"][k]) for k in row] for row in
                       (("ixx", "ixy", "ixz"), ("ixy", "iyy", "iyz"), ("ixz", "iyz", "izz"))])
        frame[:3, 3] = [float(v) for v in vals["xyz"].split()]
        back = Inertia(float(vals["mass"]), com=(0.0, 0.0, 0.0), inertia=jj, frame=frame).pseudo()
        err = float(np.abs(back - n).max()) if np.all(np.isfinite(back)) else np.inf
        if not _within_bounds(float(vals["mass"]), frame[:3, 3], jj):
            err = np.inf  # beyond the reader's bounds (model.bounds): the written file would be refused
            break
        if err <= 1e-9 * scale:
            return vals
    raise ModelError(f"{what}: mass {m:.6g} with first moment |m c| = {hn:.3g} puts the centre of mass "
                     f"{np.linalg.norm(c):.3g} m from the link frame; a URDF <inertial> re-reads it with "
                     f"relative error {err / max(scale, np.finfo(float).tiny):.2g} (> 1e-9): not representable")


def _within_bounds(m: float, c: np.ndarray, j: np.ndarray) -> bool:
    """Whether the reader would accept these values (:mod:`baseparams.model.bounds`)."""
    from ..model import bounds

    return (abs(m) <= bounds.MAX_MASS and bool(np.all(np.abs(c) <= bounds.MAX_LENGTH))
            and bool(np.all(np.abs(j) <= bounds.MAX_INERTIA)))


def _edit_inertial(edit, link, vals: dict) -> None:
    """Set a link's ``<inertial>`` values in place, adding the elements it lacks (one per line)."""
    inertia = " ".join(f'{k}="{v}"' for k, v in vals["inertia"].items())
    inl = link.find("inertial")
    if inl is None and float(vals["mass"]) == 0 and not any(float(v) for v in vals["inertia"].values()):
        return  # absent reads as zero
    if inl is None:
        edit.append(link, ["<inertial>", f'  <origin xyz="{vals["xyz"]}" rpy="0 0 0"/>',
                           f'  <mass value="{vals["mass"]}"/>', f"  <inertia {inertia}/>", "</inertial>"])
        return
    add = []
    for tag, values in (("origin", {"xyz": vals["xyz"]}), ("mass", {"value": vals["mass"]}),
                        ("inertia", vals["inertia"])):
        el = inl.find(tag)
        if el is not None:
            changed = {k: v for k, v in values.items() if not _same_numbers(el.attrs.get(k), v)}
            if changed:
                edit.set(el, **changed)
        elif tag == "origin" and vals["xyz"] == "0 0 0":
            continue  # absent reads as the origin
        else:
            add.append(f"<{tag} " + " ".join(f'{k}="{v}"' for k, v in values.items()) + "/>")
    if add:
        edit.append(inl, add)


def _same_numbers(old: str | None, new: str) -> bool:
    """Whether an attribute's text reads as the same numbers as ``new`` (then it is kept as written)."""
    try:
        return old is not None and [float(x) for x in old.split()] == [float(x) for x in new.split()]
    except ValueError:
        return False


def _edit_drives(edit, doc, source: Path, drives: dict, couplings: list) -> list[str]:
    """``<dynamics damping friction>`` and a comment of what URDF cannot hold, per joint; the notes."""
    joints = {jt.attrs.get("name"): jt for jt in doc.findall("joint")}
    unknown = [j for j in list(drives) + [j for c in couplings for j in c["joints"]] if j not in joints]
    if unknown:
        raise ModelError(f"{source}: drive terms of joints {sorted(set(unknown))[:5]} that are not in the file")
    written, held_out = 0, {}
    for name, jt in joints.items():
        terms = drives.get(name) or {}
        dyn_values = _dynamics_values(source, name, terms)
        lost = _not_in_urdf(name, terms, couplings, 2 if jt.attrs.get("type") == "prismatic" else 1, held_out)
        comment = ("<!-- baseparams: not in URDF: " + "; ".join(lost).replace("--", "- -") + " -->") if lost else None
        old = [cm for cm in jt.comments if cm[2].strip().startswith("baseparams:")]
        for k, (start, end, _) in enumerate(old):  # an earlier export's comment: replaced, not repeated
            if k == 0 and comment is not None:
                edit.replace(start, end, comment)
                comment = None
            else:
                edit.remove_line(start, end)
        dyn = jt.find("dynamics")
        if dyn_values:
            written += 1
            if dyn is not None:
                dyn_values = {k: v for k, v in dyn_values.items() if not _same_numbers(dyn.attrs.get(k), v)}
                if dyn_values:
                    edit.set(dyn, **dyn_values)
            else:
                line = "<dynamics " + " ".join(f'{k}="{v}"' for k, v in dyn_values.items()) + "/>"
                edit.append(jt, ([comment] if comment else []) + [line])
                comment = None
        if comment is not None:
            if dyn is not None:
                edit.insert_before(dyn, comment)
            else:
                edit.append(jt, [comment])
    return _drive_notes(drives, written, held_out)


def _dynamics_values(source: Path, joint: str, terms: dict) -> dict[str, str]:
    """The ``<dynamics>`` attributes of a joint's identified terms (a negative friction refused)."""
    out = {}
    for kind, attr in _URDF_DYNAMICS.items():
        v = terms.get(kind)
        if v is None:
            continue
        if not v >= 0:
            raise ModelError(f"{source}: joint {joint!r}: {_DRIVE_KINDS[kind][0]} {kind} = {v:.6g} < 0 has no URDF "
                             f"<dynamics {attr}>")
        out[attr] = _num(v)
    return out


def _not_in_urdf(joint: str, terms: dict, couplings: list, col: int, held_out: dict) -> list[str]:
    """The joint's terms a URDF cannot hold, as text; ``held_out`` gathers them by kind."""
    lost = [f"{_DRIVE_KINDS[k][0]} {k} = {_num(terms[k], 6)} {_DRIVE_KINDS[k][col]}"
            for k in ("Ia", "Fo") if terms.get(k) is not None]
    for k in ("Ia", "Fo"):
        if terms.get(k) is not None:
            held_out.setdefault(k, []).append(joint)
    for c in couplings:
        if joint in c["joints"]:
            vals = ", ".join(f"{k} {_num(c[k], 6)} {_DRIVE_KINDS[k][1]}" for k in ("Iam", "Fvm", "Fcm")
                             if isinstance(c.get(k), float))
            lost.append(f"coupled motor {c['name']} (" + ", ".join(f"{w:g} {j}" for j, w in c["joints"].items())
                        + (f"): {vals}" if vals else ")"))
            held_out.setdefault("coupled motors", []).append(c["name"])
    return lost


def _drive_notes(drives: dict, written: int, held_out: dict) -> list[str]:
    """The export's notes: the ``<dynamics>`` written, what URDF cannot hold."""
    notes = []
    if written:
        kinds = [k for k in _URDF_DYNAMICS if any(d.get(k) is not None for d in drives.values())]
        notes.append(f"--urdf: <dynamics> of {written} joints set to the identified "
                     + " and ".join(f"{_DRIVE_KINDS[k][0]} {k} ({_URDF_DYNAMICS[k]}=)" for k in kinds))
    if held_out:
        what = {"Ia": "rotor inertia (armature) Ia", "Fo": "torque offsets Fo", "coupled motors": "coupled motors"}
        notes.append("--urdf: URDF cannot hold " + ", ".join(
            f"{what[k]} ({len(set(v))} {'motors' if k == 'coupled motors' else 'joints'})" for k, v in held_out.items())
            + "; their values are in an XML comment <!-- baseparams: ... --> inside each joint")
    return notes
