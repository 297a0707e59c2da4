"""Expand a ROS xacro file (``robot.urdf.xacro``) into URDF, treating the file as untrusted input.

The expansion is ROS's own ``xacro`` package (PyPI ``xacro``, BSD; the optional extra
``baseparams[xacro]``): macros, properties, ``xacro:if``, includes, ``xacro:arg`` and YAML. A model
file may not run code, read files outside its folders, or blow up memory or time, so while a file
is expanded (one at a time, under a lock) these parts of ``xacro`` are replaced:

- ``${...}`` and ``$(eval ...)`` are interpreted by :class:`~baseparams.io.safe_expr.Evaluator` (no
  ``eval``; only math, a few builtins and xacro's helpers may be called). Stock ``xacro`` lets a
  file run any code (its filter of ``__`` names is bypassed through ``python.vars``).
- Files (includes, ``xacro.load_yaml``) are read only inside the model's folder (its ROS package,
  when a ``package.xml`` is found above it) and the package path, each a regular file of at most
  :data:`~baseparams.files.MODEL_MAX_BYTES`, at most :data:`MAX_INCLUDES` of them.
- ``$(find PKG)`` and ``package://PKG/...`` resolve from the package path: ``--package-path``
  folders, then the ``BASEPARAMS_PACKAGE_PATH`` and ``ROS_PACKAGE_PATH`` variables
  (:data:`os.pathsep`-separated), then ``AMENT_PREFIX_PATH`` (``PREFIX/share/PKG``). A folder
  named ``PKG``, or holding ``PKG`` one or two levels down, is the package; the package holding
  the model file (its ``package.xml``) is found without a package path.
- ``$(env VAR)`` is refused and ``$(optenv VAR DEFAULT)`` is ``DEFAULT`` (a model file does not
  read the environment: give values with ``--xacro-arg``); ``$(cwd)`` is refused.
- A :class:`~baseparams.io.safe_expr.Budget` bounds steps (expressions, expanded elements),
  seconds and characters produced, and at most :data:`MAX_ELEMENTS` elements are expanded;
  xacro's own messages become notes.

Errors are one line naming the file (the included file where it happened) and, when the failing
text is found in it, the line.
"""

from __future__ import annotations

import contextlib
import os
import re
import threading
from pathlib import Path

from ..errors import BaseparamsError, ModelError
from ..files import MODEL_MAX_BYTES, check_input, read_input_bytes
from .safe_expr import Budget, Evaluator, ExpressionError, bounded_range, numeric_sum

#: the environment variable of the package path (folders separated by ``os.pathsep``)
PACKAGE_PATH_ENV = "BASEPARAMS_PACKAGE_PATH"
#: the most files one expansion reads (includes and YAML files)
MAX_INCLUDES = 1000
#: the most elements one expansion visits (macro bodies and included files included)
MAX_ELEMENTS = 20_000
#: Python builtins an expression may call (xacro exposes them, directly and as ``python.NAME``)
_BUILTINS = ("list", "dict", "len", "str", "float", "int", "bool", "min", "max", "round", "abs", "all", "any",
             "divmod", "enumerate", "frozenset", "ord", "repr", "reversed", "set", "sorted", "tuple", "zip",
             "sum", "range")
#: math functions an expression may call (not factorial, comb, perm, prod: huge integers)
_MATH = ("sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "asinh", "acosh", "atanh",
         "sqrt", "cbrt", "exp", "exp2", "expm1", "log", "log10", "log2", "log1p", "pow", "fabs", "floor", "ceil",
         "trunc", "fmod", "copysign", "degrees", "radians", "hypot", "isclose", "isfinite", "isinf", "isnan",
         "modf", "frexp", "ldexp", "fsum", "gcd", "isqrt", "remainder", "dist")
_LOCK = threading.Lock()
_PKG_NAME = re.compile(r"^[A-Za-z0-9_.-]+$")


def _xacro():
    """The ``xacro`` module, or a one-line error naming the extra."""
    try:
        import xacro
    except ImportError:
        raise BaseparamsError("reading a .xacro file needs the 'xacro' package: "
                              "pip install 'baseparams[xacro]'") from None
    return xacro


def parse_xacro_args(items) -> dict[str, str]:
    """Xacro arguments from ``NAME:=VALUE`` strings (or a mapping, returned as strings).

    Parameters
    ----------
    items : iterable of str, or mapping, or None
        ``["arm:=left", "scale:=2"]`` (the CLI's ``--xacro-arg``) or ``{"arm": "left"}``.

    Returns
    -------
    dict of str to str
        Name to value.

    Raises
    ------
    BaseparamsError
        An item that is not ``NAME:=VALUE`` with a non-empty name.
    """
    if items is None:
        return {}
    if isinstance(items, dict):
        return {str(k): str(v) for k, v in items.items()}
    out = {}
    for item in items:
        name, sep, value = str(item).partition(":=")
        if not sep or not name.strip() or any(c.isspace() for c in name.strip()):
            raise BaseparamsError(f"--xacro-arg {item!r}: expected NAME:=VALUE (e.g. --xacro-arg prefix:=left_)")
        out[name.strip()] = value
    return out


def package_dirs(package_path=None) -> list[Path]:
    """The folders searched for ROS packages, in order.

    Parameters
    ----------
    package_path : str, path or list of them, optional
        Folders given by the user (``--package-path``), each possibly an ``os.pathsep``-separated list.

    Returns
    -------
    list of Path
        ``package_path``, then ``BASEPARAMS_PACKAGE_PATH``, ``ROS_PACKAGE_PATH`` and
        ``AMENT_PREFIX_PATH``'s ``share`` folders (missing folders of the variables skipped).

    Raises
    ------
    BaseparamsError
        A folder of ``package_path`` that does not exist.
    """
    given = [package_path] if isinstance(package_path, str | os.PathLike) else list(package_path or [])
    out = []
    for entry in given:
        for d in str(os.fspath(entry)).split(os.pathsep):
            if d and not Path(d).is_dir():
                raise BaseparamsError(f"--package-path {d}: not a folder")
            out += [Path(d)] if d else []
    for var in (PACKAGE_PATH_ENV, "ROS_PACKAGE_PATH", "AMENT_PREFIX_PATH"):
        for d in os.environ.get(var, "").split(os.pathsep):
            p = Path(d) / "share" if var == "AMENT_PREFIX_PATH" else Path(d)
            if d and p.is_dir():
                out.append(p)
    return out


def find_package(name: str, dirs: list[Path]) -> Path | None:
    """The folder of ROS package ``name`` in ``dirs`` (see the module doc), or None.

    Parameters
    ----------
    name : str
        The package's name (letters, digits, ``_``, ``-``, ``.``).
    dirs : list of Path
        The package path (:func:`package_dirs`).

    Returns
    -------
    Path or None
        The package's folder.
    """
    if not _PKG_NAME.match(name) or name in (".", ".."):
        return None
    for d in dirs:
        if d.name == name:
            return d
        if (d / name).is_dir():
            return d / name
        with contextlib.suppress(OSError):
            for sub in sorted(d.iterdir()):
                if sub.is_dir() and (sub / name).is_dir():
                    return sub / name
    return None


def _tokenize(s, sep=",; ", skip_empty=True):
    """``xacro.tokenize`` with the separators escaped (xacro puts them into a regular expression)."""
    parts = re.split(f"[{re.escape(str(sep))}]", str(s))
    return [p for p in parts if p] if skip_empty else parts


def _package_root(path: Path) -> tuple[Path, str | None]:
    """``(folder, name)`` of the ROS package holding ``path`` (a ``package.xml`` up to 3 levels above).

    Without one: ``(path's folder, None)``.
    """
    d = path.parent
    for cand in [d, *list(d.parents)[:3]]:
        with contextlib.suppress(BaseparamsError):
            text = read_input_bytes(cand / "package.xml", 2**20).decode("utf-8", "replace")
            m = re.search(r"<name>\s*([^<\s]+)\s*</name>", text)
            return cand, m.group(1) if m else cand.name
    return d, None


class _Session:
    """One expansion: the allowed folders, the budget, the evaluator, the notes."""

    def __init__(self, xacro, path: Path, args: dict[str, str], dirs: list[Path]):
        self.xacro, self.path, self.args, self.dirs = xacro, path, args, dirs
        self.home, self.home_name = _package_root(path.resolve())
        self.roots = {os.path.realpath(p) for p in [self.home, *dirs]}
        self.budget = Budget()
        self.notes: list[str] = []
        self.texts: dict[str, bytes] = {}
        self.reads = self.elements = 0
        self.evaluator = Evaluator(self._callables(), (xacro.NameSpace, xacro.YamlDictWrapper), self.budget)

    def _callables(self) -> list[tuple[object, object]]:
        """``(found, called)`` pairs: what an expression may call (see :class:`Evaluator`)."""
        x = self.xacro
        gs = x._global_symbols
        py, math_ns, xns = (dict(gs[k]) for k in ("python", "math", "xacro"))
        repl = {"range": bounded_range, "sum": numeric_sum}
        pairs = []
        for name in _BUILTINS:
            called = repl.get(name, py.get(name))
            pairs += [(obj, called) for obj in (py.get(name), gs.get(name)) if obj is not None]
        pairs += [(math_ns[n], math_ns[n]) for n in _MATH if n in math_ns]
        for name, called in (("arg", xns["arg"]), ("fatal", xns["fatal"]), ("tokenize", _tokenize),
                             ("dotify", x.YamlDictWrapper), ("abs_filename", self.abs_filename),
                             ("load_yaml", self.load_yaml), ("message", self.say), ("warning", self.say),
                             ("error", self.say), ("print_location", self.say)):
            pairs += [(obj, called) for obj in (xns.get(name), gs.get(name)) if obj is not None]
        return pairs + [(f, f) for f in (self.eval_arg, self.eval_find, self.eval_dirname)]

    # ---- files ----------------------------------------------------------------------------------
    def allowed(self, filename: str) -> bool:
        real = os.path.realpath(filename)
        return any(real == r or real.startswith(r.rstrip(os.sep) + os.sep) for r in self.roots)

    def read(self, filename: str) -> bytes:
        """A file's bytes: inside the allowed folders, regular, bounded; counted against the budget."""
        x = self.xacro
        self.reads += 1
        if self.reads > MAX_INCLUDES:
            raise x.XacroException(f"more than {MAX_INCLUDES} files read (a model file's limit)")
        if not self.allowed(filename):
            raise x.XacroException(f"{filename}: outside the model's folder and the package path "
                                   f"(a model file may not read other files; --package-path adds folders)")
        if not os.path.exists(filename):
            raise x.XacroException(f"{filename}: no such file", exc=FileNotFoundError(filename))
        try:
            data = read_input_bytes(os.path.realpath(filename), MODEL_MAX_BYTES, error=ModelError)
        except ModelError as exc:
            raise x.XacroException(str(exc)) from None
        self.budget.room(len(data), f"reading {filename}")
        self.budget.chars += len(data)
        self.texts[filename] = data
        return data

    def parse(self, inp, filename=None):
        """``xacro.parse``: a file is read by :meth:`read`."""
        import xml.dom.minidom

        if inp is not None:
            return self.original["parse"](inp, filename)
        try:
            data = self.read(filename)
        except self.xacro.XacroException:
            if self.xacro.filestack and self.xacro.filestack[-1] == filename and len(self.xacro.filestack) > 1:
                self.xacro.filestack.pop()  # name the including file, as xacro does
            raise
        return xml.dom.minidom.parseString(data)

    def abs_filename(self, spec):
        """``xacro.abs_filename_spec``, with ``package://PKG/...`` resolved from the package path."""
        spec = str(spec)
        if spec.startswith("package://"):
            pkg, _, rest = spec[len("package://"):].partition("/")
            return os.path.join(self.eval_find(pkg), rest)
        return self.original["abs_filename_spec"](spec)

    def load_yaml(self, filename):
        """``xacro.load_yaml`` confined: YAML read by :meth:`read`, with xacro's unit tags."""
        import yaml

        class Loader(yaml.SafeLoader):
            pass

        for unit in self.xacro.ConstructUnits:
            Loader.add_constructor(unit.value.tag, unit.constructor)
        name = self.abs_filename(filename)
        try:
            data = yaml.load(self.read(name), Loader=Loader)  # noqa: S506 (a SafeLoader)
        except yaml.YAMLError as exc:
            raise self.xacro.XacroException(f"{name}: invalid YAML ({' '.join(str(exc).split())})") from None
        return self.xacro.YamlListWrapper.wrap(data)

    def glob(self, pattern: str) -> list[str]:
        """``glob.glob`` for xacro's wildcard includes: only inside the allowed folders, no ``..`` after a wildcard."""
        import glob as _glob

        head = re.split(r"[*?\[]", pattern, maxsplit=1)[0]
        if ".." in pattern[len(head):].replace("\\", "/").split("/") or not self.allowed(os.path.dirname(head) or "."):
            raise self.xacro.XacroException(f"{pattern}: a wildcard include outside the model's folder and the "
                                            f"package path")
        found = sorted(_glob.glob(pattern))
        if len(found) > MAX_INCLUDES:
            raise self.xacro.XacroException(f"{pattern}: more than {MAX_INCLUDES} files")
        return found

    # ---- substitutions and expressions ----------------------------------------------------------
    def say(self, *args, **kwargs) -> str:
        """Xacro's messages (``xacro.warning(...)``, its own warnings): notes."""
        text = " ".join(" ".join(str(a).split()) for a in args)
        if text:
            self.notes.append(f"{self.path}: xacro: {text}")
        return ""

    def eval_arg(self, name):
        """``$(arg NAME)``: the value given (``--xacro-arg``) or the file's default."""
        try:
            return self.xacro.substitution_args_context["arg"][name]
        except KeyError:
            raise self.xacro.XacroException(f"undefined xacro argument {name!r} (give it with --xacro-arg "
                                            f"{name}:=VALUE)") from None

    def eval_find(self, pkg):
        """``$(find PKG)``: the package's folder, from the package path."""
        found = self.home if pkg == self.home_name else find_package(str(pkg), self.dirs)
        if found is None:
            where = ", ".join(str(d) for d in self.dirs) or "none"
            raise self.xacro.XacroException(f"$(find {pkg}): package {pkg!r} not found in the package path "
                                            f"(--package-path DIR or {PACKAGE_PATH_ENV}; searched: {where})")
        self.roots.add(os.path.realpath(found))
        return str(found)

    def eval_dirname(self):
        """``$(dirname)``: the folder of the file being expanded."""
        stack = self.xacro.filestack or [str(self.path)]
        return os.path.abspath(os.path.dirname(stack[-1] or str(self.path)))

    def extension(self, s: str):
        """``xacro.eval_extension``: one ``$(...)`` substitution (see the module doc)."""
        inner = s[2:-1].strip()
        if inner.startswith("eval "):
            return str(self.evaluator.evaluate(inner[5:], self._eval_lookup))
        cmd, *a = inner.split() or [""]
        if cmd == "arg" and len(a) == 1:
            return self.eval_arg(a[0])
        if cmd == "find" and len(a) == 1:
            return self.eval_find(a[0])
        if cmd == "dirname" and not a:
            return self.eval_dirname()
        if cmd == "optenv" and a:
            self.notes.append(f"{self.path}: xacro: $(optenv {a[0]}) is its default {' '.join(a[1:])!r} (a model "
                              f"file does not read the environment)")
            return " ".join(a[1:])
        if cmd in ("env", "optenv", "cwd"):
            raise self.xacro.XacroException(f"$({inner}): a model file may not read the environment or the "
                                            f"working folder (give values with --xacro-arg NAME:=VALUE)")
        raise self.xacro.XacroException(f"$({inner}): unknown or malformed substitution (known: arg, find, "
                                        f"dirname, eval, optenv)")

    def _eval_lookup(self, name: str):
        """Names in ``$(eval ...)``: functions, booleans, math, then the arguments (as numbers when they are)."""
        fixed = {"arg": self.eval_arg, "find": self.eval_find, "dirname": self.eval_dirname,
                 "true": True, "false": False}
        if name in fixed:
            return fixed[name]
        math_ns = self.xacro._global_symbols["math"]
        if name in math_ns:
            return dict.__getitem__(math_ns, name)
        value = self.xacro.substitution_args_context["arg"][name]  # KeyError: undefined
        for conv in (int, float):
            with contextlib.suppress(ValueError):
                return conv(value)
        return {"true": True, "false": False}.get(value.lower(), value)

    def safe_eval(self, expr, globals, locals=None):  # noqa: A002 (xacro's signature)
        """``xacro.safe_eval``: ``${...}`` interpreted by the restricted evaluator."""
        return self.evaluator.evaluate(expr, globals.__getitem__)

    def eval_text(self, text, symbols):
        """``xacro.eval_text``, counted: each evaluated text is a step and its result is charged."""
        self.budget.step()
        return self.budget.charge(self.original["eval_text"](text, symbols))

    def eval_all(self, node, macros, symbols):
        """``xacro.eval_all``, counted: at most :data:`MAX_ELEMENTS` elements expanded (exponential macros stop).

        minidom inserts a node in O(siblings), so a flat expansion of n elements costs O(n^2): the
        bound keeps that below seconds (real robots expand to a few thousand elements).
        """
        self.budget.step()
        self.elements += 1
        if self.elements > MAX_ELEMENTS:
            raise ExpressionError(f"more than {MAX_ELEMENTS} elements expanded (a model file's limit)")
        return self.original["eval_all"](node, macros, symbols)

    # ---- patching -------------------------------------------------------------------------------
    @contextlib.contextmanager
    def patched(self):
        """Replace xacro's evaluation, file reading and messages by this session's, then restore them."""
        x = self.xacro
        new = {"safe_eval": self.safe_eval, "eval_extension": self.extension, "parse": self.parse, "glob": self,
               "abs_filename_spec": self.abs_filename, "eval_text": self.eval_text, "eval_all": self.eval_all,
               "warning": self.say, "message": lambda *a, **k: None, "error": self.say,
               "print_location": lambda *a, **k: None}
        self.original = {k: getattr(x, k) for k in new}
        try:
            for k, v in new.items():
                setattr(x, k, v)
            yield
        finally:
            for k, v in self.original.items():
                setattr(x, k, v)
            x.substitution_args_context["arg"] = {}
            x.all_includes.clear()
            x.filestack, x.macrostack = None, None


def expand_xacro(path, args=None, package_path=None, files: list | None = None) -> tuple[bytes, list[str]]:
    """The URDF text of a xacro file, expanded safely (see the module doc), and notes.

    Parameters
    ----------
    path : str or path
        The ``.xacro`` file.
    args : mapping or iterable of str, optional
        xacro arguments: ``{"NAME": "VALUE"}`` or ``["NAME:=VALUE", ...]`` (:func:`parse_xacro_args`).
    package_path : str, path or list of them, optional
        Folders searched for ``$(find PKG)`` and ``package://PKG`` before the environment's
        (:func:`package_dirs`).
    files : list, optional
        Extended with the paths of the files read (the model, its includes, YAML), also when the
        expansion fails (those read until then).

    Returns
    -------
    data : bytes
        The expanded document (UTF-8 XML).
    notes : list of str
        xacro's warnings and the substitutions not taken from the environment, each prefixed with the path.

    Raises
    ------
    BaseparamsError
        The ``xacro`` package missing (naming the extra), a bad argument or package folder.
    ModelError
        Any error of the expansion, one line naming the file (and the line when found): malformed
        XML, an undefined property, argument or macro, a package not found, a file outside the
        allowed folders, an expression a model file may not use, a budget exceeded.
    """
    x = _xacro()
    p = check_input(path, MODEL_MAX_BYTES, error=ModelError)
    try:  # the safe session replaces parts of xacro's module (written against xacro 2.1)
        sess = _Session(x, p, parse_xacro_args(args), package_dirs(package_path))
    except (AttributeError, KeyError, TypeError) as exc:
        raise BaseparamsError(f"xacro {getattr(x, '__version__', '(unknown version)')} is not supported: its "
                              f"internals differ ({type(exc).__name__}: {exc}); "
                              "pip install 'xacro>=2.1,<2.2'") from None
    with _LOCK, sess.patched():
        try:
            x.init_stacks(str(p))
            doc = x.parse(None, str(p))
            x.process_doc(doc, mappings=dict(sess.args), verbosity=0)
            data = doc.toxml(encoding="utf-8")
        except Exception as exc:  # noqa: BLE001 (every failure of the expansion is one line)
            raise ModelError(_message(sess, exc)) from None
        finally:
            if files is not None:
                files.extend(sess.texts)
    if len(data) > MODEL_MAX_BYTES:
        raise ModelError(f"{p}: the expanded document is larger than {MODEL_MAX_BYTES} bytes")
    return data, sess.notes


#: the text to look for in a file, for the line of an error, from xacro's messages
_NEEDLES = ((re.compile(r"unknown macro name: (\S+)"), "<{}"),
            (re.compile(r"undefined xacro argument '([^']*)'"), "$(arg {}"),
            (re.compile(r"\$\(find (\S+?)\)"), "$(find {}"),
            (re.compile(r"\$\(find (\S+?)\)"), "package://{}/"),
            (re.compile(r"^(?:\S*/)?([^/\s]+): (?:outside the model's folder|no such file|not a regular)"), "{}"),
            (re.compile(r"^\$\((.*?)\):"), "$({}"))


def _message(sess: _Session, exc: Exception) -> str:
    """One line for a failed expansion: ``FILE[:LINE]: xacro: problem [(included from TOP)]``."""
    import xml.parsers.expat

    x = sess.xacro
    stack = [f for f in (x.filestack or []) if f] or [str(sess.path)]
    where, line = stack[-1], None
    if isinstance(exc, xml.parsers.expat.ExpatError):
        text = f"malformed XML ({xml.parsers.expat.ErrorString(exc.code)}, column {exc.offset})"
        line = exc.lineno
    elif isinstance(exc, RecursionError):
        text = "nested too deeply (a macro or an include that uses itself?)"
    elif isinstance(exc, MemoryError):
        text = "out of memory"
    elif isinstance(exc, x.XacroException | ExpressionError | BaseparamsError):
        raw = str(exc)
        text = _short(raw)
        files = [m.history[-1][-1] for m in reversed(x.macrostack or []) if m.history and m.history[-1]]
        where, line = _locate(sess, raw, [where, *files], where)
    else:
        text = f"{type(exc).__name__}: {' '.join(str(exc).split())}"
    top = str(sess.path)
    origin = "" if os.path.abspath(where) == os.path.abspath(top) else f" (included from {top})"
    return f"{where}{'' if line is None else f':{line}'}: xacro: {text}{origin}"


_EVALUATING = re.compile(r"\s*when evaluating expression '(.*?)'(?=\s*when evaluating|\s*$)", re.S)


def _short(raw: str) -> str:
    """Xacro's message on one line: the innermost expression named once, shortened to 100 characters."""
    exprs = _EVALUATING.findall(raw)
    text = " ".join(_EVALUATING.sub("", raw).split())
    if exprs:
        e = " ".join(exprs[0].split())
        text += f" (evaluating '{e[:100]}{'...' if len(e) > 100 else ''}')"
    return text


def _locate(sess: _Session, raw: str, files: list[str], default: str) -> tuple[str, int | None]:
    """``(file, line)`` of the first line holding the failing text (xacro gives no line numbers)."""
    needles = ["${" + e for e in _EVALUATING.findall(raw)]
    needles += [fmt.format(m.group(1)) for pattern, fmt in _NEEDLES if (m := pattern.search(raw))]
    for needle in (n.encode() for n in needles):
        for f in files:
            data = sess.texts.get(f)
            if data is not None and needle in data:
                return f, data[:data.index(needle)].count(b"\n") + 1
    return default, None
