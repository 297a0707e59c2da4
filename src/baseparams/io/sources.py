"""Every file a robot model reads, and the checks on them before MuJoCo (or anything) opens one.

A model is more than its file: an MJCF file includes other files (``<include>``, recursively), reads
meshes, height fields, textures and skins; a xacro file includes files and YAML; a URDF names
meshes (MuJoCo reads them when it imports the URDF). :func:`model_files` lists them all (as they
exist on disk, symbolic links resolved): what the output guard protects
(:func:`baseparams.files.refuse_inputs`: no output of a run lands on any file its model reads).

:func:`mjcf_sources` runs before MuJoCo parses an MJCF file (MuJoCo reads what it is given:
a FIFO include blocks it for ever; ``<size nuserdata="6.5e8">`` allocates 4.7 GB at compile):

* every include and asset file that exists is a regular file (no FIFO, device, folder, no link to
  ``/dev/zero``), includes at most :data:`~baseparams.files.MODEL_MAX_BYTES` each, assets at most
  :data:`ASSET_MAX_BYTES` each and :data:`ASSETS_MAX_BYTES` together, at most :data:`MAX_FILES`
  files, includes nested at most :data:`MAX_INCLUDE_DEPTH` deep;
* what MuJoCo allocates from numbers in the file is bounded: ``<size>``'s counts and ``memory``
  (:data:`SIZE_LIMITS`), built-in textures' pixels, height fields' samples, and the bodies made by
  ``<replicate>``, ``<composite>`` and ``<flexcomp>`` (their counts multiplied through nesting).

A missing file is not an error here: MuJoCo's own message (or the asset stripping of
:mod:`baseparams.io.mjcf`) says what is missing.
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from ..errors import ModelError
from ..files import MODEL_MAX_BYTES, check_input, read_input_bytes

#: the largest mesh, texture, height field or skin file read [bytes]
ASSET_MAX_BYTES = 256 * 2**20
#: the largest total of a model's asset files [bytes]
ASSETS_MAX_BYTES = 1024 * 2**20
#: the most files (includes and assets) one model reads
MAX_FILES = 10_000
#: the deepest nesting of ``<include>``
MAX_INCLUDE_DEPTH = 32
#: ``<size>`` attributes MuJoCo allocates from, and the largest value accepted (``memory`` in bytes)
SIZE_LIMITS = {"memory": 2**30, "nuserdata": 10**7, "nkey": 10**5, "nconmax": 10**6, "njmax": 10**6,
               "nstack": 10**8, "nuser_body": 10**3, "nuser_jnt": 10**3, "nuser_geom": 10**3, "nuser_site": 10**3,
               "nuser_cam": 10**3, "nuser_tendon": 10**3, "nuser_actuator": 10**3, "nuser_sensor": 10**3}
#: the most pixels of a built-in texture (all faces), samples of a height field, bodies made by counts
MAX_PIXELS = 2**26
MAX_HFIELD = 10**7
MAX_MADE = 10**5
#: asset elements and their file attributes
_ASSET_FILES = {"mesh": ("file",), "hfield": ("file",), "skin": ("file",), "model": ("file",),
                "texture": ("file", "fileright", "fileleft", "fileup", "filedown", "filefront", "fileback")}
_MEMORY = re.compile(r"^\s*(\d+(?:\.\d*)?(?:[eE][-+]?\d+)?)\s*([KMGTP]?)\s*(?:[bB])?\s*$")


def _parse(path: Path, what: str) -> ET.Element | None:
    """A file's XML root (None when it does not parse: its reader says why)."""
    data = read_input_bytes(path, MODEL_MAX_BYTES, error=ModelError)
    try:
        return ET.fromstring(data.lstrip(b"\xef\xbb\xbf \t\r\n").rstrip(b" \t\r\n\x00"))
    except ET.ParseError:
        return None


def _regular(path: Path, limit: int, what: str) -> int:
    """Refuse a referenced file that is not regular or too large; its size."""
    try:
        check_input(path, limit, error=ModelError)
    except ModelError as exc:
        raise ModelError(f"{exc} ({what})") from None
    return path.stat().st_size


def _candidates(file: str, dirs: list[Path]) -> list[Path]:
    """Where a reader may find ``file``: as given when absolute, else under each folder; existing ones."""
    f = Path(file)
    if f.is_absolute():
        return [f] if os.path.lexists(f) else []
    out = []
    for d in dirs:
        for p in (d / f, d / f.name):
            if os.path.lexists(p) and p not in out:
                out.append(p)
    return out


def _number(text: str | None, what: str) -> float:
    try:
        return float(text)
    except (TypeError, ValueError):
        return 0.0  # not a number: MuJoCo's own message


def mjcf_sources(path, check: bool = True) -> list[Path]:
    """The files an MJCF model reads besides itself (includes, recursively, and assets), checked.

    Parameters
    ----------
    path : str or Path
        The MJCF file.
    check : bool
        Check them (module doc) as they are found; False: only list them.

    Returns
    -------
    list of Path
        The existing files, includes first (as found: a link is listed as named).

    Raises
    ------
    ModelError
        With ``check``: a file that is not regular or too large, too many files or includes
        nested too deep, a number in the file that makes MuJoCo allocate beyond the bounds.
    """
    main = Path(path)
    base = main.parent
    files: list[Path] = []
    seen: set[str] = set()
    dirs = {"mesh": [base], "texture": [base]}
    total = 0
    stack = [(main, 0)]
    roots = []
    while stack:
        f, depth = stack.pop()
        root = _parse(f, str(f))
        if root is None:
            continue
        roots.append((f, root))
        for comp in root.iter("compiler"):
            for attr, kinds in (("assetdir", ("mesh", "texture")), ("meshdir", ("mesh",)),
                                ("texturedir", ("texture",))):
                if comp.get(attr):
                    for k in kinds:
                        dirs[k].insert(0, base / comp.get(attr))
        for inc in root.iter("include"):
            name = inc.get("file")
            if not name:
                continue
            for p in _candidates(name, [f.parent, base]):
                key = os.path.realpath(p)
                if key in seen:
                    continue
                seen.add(key)
                files.append(p)
                if check:
                    if depth + 1 > MAX_INCLUDE_DEPTH:
                        raise ModelError(f"{main}: <include> nested more than {MAX_INCLUDE_DEPTH} deep ({p})")
                    if len(files) > MAX_FILES:
                        raise ModelError(f"{main}: reads more than {MAX_FILES} files")
                    _regular(p, MODEL_MAX_BYTES, f"included by {f}")
                stack.append((p, depth + 1))
    for f, root in roots:
        total = _assets(main, f, root, dirs, base, files, seen, total, check)
        if check:
            _check_allocations(f, root)
    return files


def _assets(main: Path, f: Path, root: ET.Element, dirs: dict, base: Path, files: list, seen: set, total: int,
            check: bool) -> int:
    """The asset files one MJCF file names, added to ``files`` (checked with ``check``); the bytes so far."""
    for tag, attrs in _ASSET_FILES.items():
        for el in root.iter(tag):
            for attr in attrs:
                name = el.get(attr)
                if not name:
                    continue
                where = dirs["texture" if tag == "texture" else "mesh"] + [f.parent, base]
                for p in _candidates(name, where):
                    key = os.path.realpath(p)
                    if key in seen:
                        continue
                    seen.add(key)
                    files.append(p)
                    if not check:
                        continue
                    if len(files) > MAX_FILES:
                        raise ModelError(f"{main}: reads more than {MAX_FILES} files")
                    total += _regular(p, ASSET_MAX_BYTES, f"<{tag} {attr}> of {f}")
                    if total > ASSETS_MAX_BYTES:
                        raise ModelError(f"{main}: its asset files take more than {ASSETS_MAX_BYTES / 2**20:.0f} MB "
                                         "together")
    return total


def _check_allocations(f: Path, root: ET.Element) -> None:
    """Numbers in one MJCF file that make MuJoCo allocate: ``<size>``, textures, height fields, counts."""
    for size in root.iter("size"):
        for attr, limit in SIZE_LIMITS.items():
            text = size.get(attr)
            if text is None:
                continue
            if attr == "memory":
                m = _MEMORY.match(text)
                value = float(m.group(1)) * 1024 ** " KMGTP".index(m.group(2) or " ") if m else 0.0
            else:
                value = _number(text, attr)
            if value > limit:
                raise ModelError(f"{f}: <size {attr}=\"{text}\">: MuJoCo would allocate for {value:.3g}"
                                 f"{' bytes' if attr == 'memory' else ''}; at most {limit:g} here (not a robot's size)")
    for tex in root.iter("texture"):
        w, h = _number(tex.get("width", "0"), "width"), _number(tex.get("height", "0"), "height")
        faces = 6 if tex.get("type") in ("cube", "skybox") else 1
        if w * max(h, 1.0) * faces > MAX_PIXELS:
            raise ModelError(f"{f}: <texture name={tex.get('name')!r}> {w:g} x {h:g} pixels: at most {MAX_PIXELS} here")
    for hf in root.iter("hfield"):
        n = _number(hf.get("nrow", "0"), "nrow") * _number(hf.get("ncol", "0"), "ncol")
        if n > MAX_HFIELD:
            raise ModelError(f"{f}: <hfield name={hf.get('name')!r}> {n:.3g} samples: at most {MAX_HFIELD} here")
    _check_counts(f, root, 1.0)


def _check_counts(f: Path, el: ET.Element, factor: float) -> None:
    """Bodies made by ``<replicate count>``, ``<composite count>``, ``<flexcomp count>``, through nesting."""
    stack = [(el, factor)]
    while stack:
        node, k = stack.pop()
        if node.tag in ("replicate", "composite", "flexcomp"):
            made = 1.0
            for c in (node.get("count") or "1").split():
                made *= max(_number(c, "count"), 1.0)
            k *= made
            if k > MAX_MADE:
                raise ModelError(f"{f}: <{node.tag} count=\"{node.get('count')}\">: makes {k:.3g} elements "
                                 f"(with the counts around it); at most {MAX_MADE} here")
        stack += [(c, k) for c in node]


def urdf_meshes(path, root: ET.Element | None = None, package_path=None) -> list[Path]:
    """The existing mesh files a URDF names (relative, ``file://`` or ``package://`` when the package is found).

    Parameters
    ----------
    path : str or Path
        The URDF file.
    root : xml.etree.ElementTree.Element, optional
        Its parsed root (default: read and parsed here).
    package_path : str, path or list of them, optional
        Folders of ROS packages (:func:`baseparams.io.xacro_in.package_dirs`).

    Returns
    -------
    list of Path
        The mesh files found.
    """
    from .xacro_in import find_package, package_dirs

    p = Path(path)
    if root is None:
        root = _parse(p, str(p))
        if root is None:
            return []
    out: list[Path] = []
    dirs = None
    for mesh in root.iter("mesh"):
        name = mesh.get("filename") or ""
        if name.startswith("file://"):
            name = name[len("file://"):]
        if name.startswith("package://"):
            pkg, _, rest = name[len("package://"):].partition("/")
            if dirs is None:
                try:
                    dirs = package_dirs(package_path)
                except Exception:  # noqa: BLE001 - a bad folder is the loader's message
                    dirs = []
            found = find_package(pkg, dirs)
            cands = _candidates(rest, [found]) if found else []
        else:
            cands = _candidates(name, [p.parent]) if name else []
        out += [c for c in cands if c not in out]
        if len(out) > MAX_FILES:
            break
    return out


def check_urdf_meshes(path, package_path=None) -> None:
    """Refuse a URDF whose mesh files are not regular or too large (before MuJoCo imports it).

    Parameters
    ----------
    path : str or Path
        The URDF file.
    package_path : str, path or list of them, optional
        Folders of ROS packages.

    Raises
    ------
    ModelError
        A mesh that is a FIFO, a device, a folder, larger than :data:`ASSET_MAX_BYTES`.
    """
    total = 0
    for m in urdf_meshes(path, package_path=package_path):
        total += _regular(m, ASSET_MAX_BYTES, f"<mesh filename> of {path}")
        if total > ASSETS_MAX_BYTES:
            raise ModelError(f"{path}: its mesh files take more than {ASSETS_MAX_BYTES / 2**20:.0f} MB together")


def model_files(model, xacro_args=None, package_path=None) -> list[Path]:
    """Every file a model reads: the file, its includes and assets (MJCF), includes and YAML (xacro), meshes.

    A built-in name (not a file) reads none. Nothing is checked here (the loader checks); a
    model that cannot be expanded or parsed lists what was found before.

    Parameters
    ----------
    model : str or path
        The model (a robot file or a built-in name).
    xacro_args : mapping or iterable of str, optional
        A xacro file's arguments.
    package_path : str, path or list of them, optional
        Folders of ROS packages.

    Returns
    -------
    list of Path
        The files, the model first.
    """
    p = Path(os.fspath(model))
    if not p.is_file():
        return []
    out = [p]
    suffix = p.suffix.lower()
    try:
        if suffix in (".xml", ".mjcf"):
            out += mjcf_sources(p, check=False)
        elif suffix == ".urdf":
            out += urdf_meshes(p, package_path=package_path)
        elif suffix == ".xacro":
            from .xacro_in import expand_xacro

            read: list[str] = []
            data, _ = expand_xacro(p, xacro_args, package_path, files=read)
            out += [Path(f) for f in read if Path(f) != p]
            root = ET.fromstring(data)
            out += urdf_meshes(p, root, package_path)
    except Exception:  # noqa: BLE001 - the loader reports the model's problems; the guard keeps what it found
        pass
    return out
