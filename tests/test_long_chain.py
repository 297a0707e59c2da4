"""Bodies far from the world origin (issue 46: a 10 000-link chain): rank decisions about each body's
own origin, the same count and regrouping wherever the robot stands, a one-line refusal beyond what
double precision can tell, and a long chain analysed end to end."""

from __future__ import annotations

import re
import time
from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest

import baseparams as bp
from baseparams.base.recursive import recursive_base_parameters
from baseparams.cli import main
from baseparams.errors import BaseparamsError
from baseparams.nullspace.drng import drng
from baseparams.nullspace.structured import independent_columns

from erd import pinocchio_nullity

LINK = 0.3  # m


def chain_urdf(n: int) -> str:
    """``n`` links of 0.3 m in series, axes alternating z and y (issue 46's chain)."""
    inertial = ('<inertial><origin xyz="0.01 0.02 0.15"/><mass value="1"/><inertia ixx="0.01" ixy="0.001" '
                'ixz="0" iyy="0.012" iyz="0" izz="0.004"/></inertial>')
    text = ['<robot name="chain">', f'<link name="l0">{inertial}</link>']
    for i in range(1, n + 1):
        axis = "0 0 1" if i % 2 else "0 1 0"
        text += [f'<joint name="j{i}" type="revolute"><parent link="l{i - 1}"/><child link="l{i}"/>'
                 f'<origin xyz="0 0 {LINK if i > 1 else 0.0}"/><axis xyz="{axis}"/>'
                 f'<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>',
                 f'<link name="l{i}">{inertial}</link>']
    return "\n".join(text + ["</robot>"])


def _moved(robot, distance: float, rng):
    """The same robot with its base ``distance`` away from the world origin (a fixed base: the same dynamics)."""
    shift = np.eye(4)
    d = rng.normal(size=3)
    shift[:3, 3] = distance * d / np.linalg.norm(d)
    return replace(robot, M0=shift @ robot.M0)


@pytest.mark.parametrize("seed", range(4))
def test_count_and_regrouping_do_not_depend_on_where_the_robot_stands(seed):
    """A random tree 3 km from the origin (~4 000 of its length scales): DRNG's rank, the compact basis and
    the regrouping in link frames (khalil) are the tree's at the origin. Before, the world-frame blocks'
    ``D^2``, ``D``, 1 entries (condition ~D^4) read as rank deficiency: directions lost, then
    'columns not independent on their highest body'."""
    rng = np.random.default_rng(seed)
    robot = bp.robots.random_robot(rng, 8, "RP")
    far = _moved(robot, 3000.0, rng)
    near_res, far_res = drng(robot), drng(far)
    assert far_res.rank == near_res.rank
    near, away = independent_columns(robot, near_res), independent_columns(far, far_res)
    assert near is not None and away is not None and len(away) == len(near)
    a, b = recursive_base_parameters(robot, near, "khalil"), recursive_base_parameters(far, away, "khalil")
    assert np.array_equal(a.dependent, b.dependent)
    ka, kb = np.asarray(a.K), np.asarray(b.K)
    assert np.abs(ka - kb).max() <= 1e-5 * np.abs(ka).max()  # the rounding of world blocks 3 km out: ~eps (D/L)^2
    assert bp.analyze(far, verify=False).nullity == near_res.rank


def test_too_far_is_refused_in_one_line():
    """Beyond ~20 000 length scales the world-frame columns' rounding leaves no rank decision standing."""
    rng = np.random.default_rng(1)
    far = _moved(bp.robots.random_robot(rng, 5, "RP"), 1e5, rng)
    with pytest.raises(BaseparamsError, match=r"from the world origin.*put the model's origin near its bodies") as err:
        bp.analyze(far, verify=False)
    assert "\n" not in str(err.value) and "b" in str(err.value)


def _per_link_nullity(tmp_path) -> tuple[int, int]:
    """Pinocchio's rank deficiency of the 8- and 10-link chains: ``(nullity(8), per added link)``."""
    out = []
    for n in (8, 10):
        path = tmp_path / f"chain{n}.urdf"
        path.write_text(chain_urdf(n))
        with np.errstate(divide="ignore"):
            nullity, gap = pinocchio_nullity(pin.buildModelFromUrdf(str(path)), path, 60)
        assert gap > 1e6
        out.append(nullity)
    assert (out[1] - out[0]) % 2 == 0
    return out[0], (out[1] - out[0]) // 2


def _shifted(expressions: list[dict], link: int, to: int) -> dict[str, str]:
    """The expressions of link ``link``'s parameters with every link index moved by ``to - link``."""
    def move(s: str) -> str:
        return re.sub(r"\bl(\d+)\.", lambda m: f"l{int(m.group(1)) - link + to}.", s)

    return {move(e["name"]): move(e["expression"]) for e in expressions if e["name"].startswith(f"l{link}.")}


@pytest.mark.slow
def test_long_chain_analysed(tmp_path, capsys):
    """A 2 000-link chain read from its URDF (600 m long): ``analyze --no-verify`` and the certified
    analysis give Pinocchio's count extrapolated link by link (identical links each add the same), and
    link 1 900's regrouping in link frames is link 100's (it was a RuntimeError from ~1 050 links on,
    after a wrong count; the paper convention's world-frame coefficients grow with the height)."""
    n = 2000
    first, per_link = _per_link_nullity(tmp_path)
    expected = first + per_link * (n - 8)
    path = tmp_path / "chain.urdf"
    path.write_text(chain_urdf(n))
    t0 = time.perf_counter()
    assert main(["analyze", str(path), "--no-verify", "--json"]) == 0
    seconds = time.perf_counter() - t0
    out = capsys.readouterr().out
    import json

    d = json.loads(out)
    assert d["nullity"] == expected and d["drng"]["notes"] == []
    deep, shallow = _shifted(d["base_parameters"], 1900, 100), _shifted(d["base_parameters"], 100, 100)
    assert d["convention"] == "khalil" and deep == shallow and len(deep) >= 3
    a = bp.analyze(bp.load(str(path)))
    assert a.status == "certified" and a.nullity == expected and a.certificate.completed == 0
    assert seconds < 60  # linear in the links: ~3 s on the benchmark machine
